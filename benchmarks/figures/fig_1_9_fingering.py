"""Reproduce thesis Fig. 1.9: viscous fingering in a heterogeneous 2-D core without polymer (M = 2.5) and its
suppression by 0.25 wt % polymer (M = 0.5).

The case (``spflow.plugins.forward.two_d.fingering_case``): phi = 0.21, S_wi = 0.30, mu_o/mu_w = 20, log-normal
permeability field (log-k variance 0.1, exponential covariance, correlation lengths 0.1 of the core in x and y,
seeded), 400 x 80 cells by default. Draws the permeability, the water-saturation maps of both floods at equal
injected PV, the recovery and water-cut curves, and marks water breakthrough (first output with a produced water cut
above 1 %); on the polymer maps a white contour marks the polymer front (half the injected concentration; ahead
of it moves the bank of displaced connate water). Writes ``docs/figures/fig_1_9_fingering.png`` and the numbers to
``docs/figures/fig_1_9_fingering.json``.

Run: ``.venv/bin/python benchmarks/figures/fig_1_9_fingering.py [--nx 400 --ny 80 --pv 1.0 --maps 0.1 0.2
--seed 1 --pressure-every 1]`` (the full grid takes minutes; ``--nx 100 --ny 20`` for a quick look). The
pressure is solved at every step (IMPES) by default.
"""

import argparse
import json
import sys
import time
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))

from spflow.plugins.forward.simulate import simulate  # noqa: E402
from spflow.plugins.forward.two_d import permeability_field  # noqa: E402
from spflow.plugins.forward.two_d.fingering_case import (  # noqa: E402
    end_point_mobility_ratio, fingering_effects, fingering_params, fingering_schedule)

BREAKTHROUGH_WATER_CUT = 0.01


def breakthrough_pv(ds) -> float:
    """First output PV with a produced water cut (1 - oil cut) above 1 %."""
    wc = 1.0 - ds.oil_cut.values
    hit = np.nonzero(wc > BREAKTHROUGH_WATER_CUT)[0]
    return float(ds.pv.values[hit[0]]) if hit.size else float("nan")


def run_cases(nx, ny, pv, maps, seed, pressure_every):
    params = fingering_params()
    perm = permeability_field(nx, ny, mean_md=700.0, seed=seed)
    out = {}
    for polymer in (False, True):
        start = time.perf_counter()
        ds = simulate(fingering_schedule(polymer, pv), params, cells=(nx, ny), permeability=perm,
                      effects=fingering_effects(), pv_step=0.01, profiles_at=maps, pressure_every=pressure_every)
        out[polymer] = (ds, time.perf_counter() - start)
    return params, perm, out


def main(argv=None) -> Path:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--nx", type=int, default=400)
    parser.add_argument("--ny", type=int, default=80)
    parser.add_argument("--pv", type=float, default=1.0)
    parser.add_argument("--maps", type=float, nargs="+", default=[0.1, 0.2])
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--pressure-every", type=int, default=1)
    parser.add_argument("--out", type=Path, default=ROOT / "docs" / "figures" / "fig_1_9_fingering.png")
    args = parser.parse_args(argv)

    params, perm, runs = run_cases(args.nx, args.ny, args.pv, args.maps, args.seed, args.pressure_every)
    n_maps = len(args.maps)
    fig = plt.figure(figsize=(11.0, 2.2 + 1.6 * (n_maps + 1)))
    grid = fig.add_gridspec(n_maps + 1, 3, width_ratios=[1.0, 1.0, 0.04])
    aspect = runs[False][0].attrs["aspect"]
    extent = (0.0, 1.0, 0.0, aspect)
    ax = fig.add_subplot(grid[0, 0])
    im = ax.imshow(np.log(perm.values), origin="lower", extent=extent, cmap="viridis", aspect="auto")
    ax.set_title(f"ln k (mD), {args.nx} x {args.ny}, seed {args.seed}", fontsize=9)
    fig.colorbar(im, ax=ax, fraction=0.04)
    ax = fig.add_subplot(grid[0, 1])
    numbers = {"nx": args.nx, "ny": args.ny, "seed": args.seed, "pressure_every": args.pressure_every,
               "sample_log_k_variance": float(np.var(np.log(perm.values)))}
    for polymer, colour in ((False, "tab:red"), (True, "tab:blue")):
        ds, wall = runs[polymer]
        label = "0.25 wt % polymer" if polymer else "water"
        m = end_point_mobility_ratio(params, polymer)
        bt = breakthrough_pv(ds)
        ax.plot(ds.pv, ds.recovery, color=colour, label=f"{label} (M = {m:.2g}), BT {bt:.2f} PV")
        ax.plot(ds.pv, 1.0 - ds.oil_cut, color=colour, ls="--", lw=0.8)
        ax.axvline(bt, color=colour, ls=":", lw=0.8)
        key = "polymer" if polymer else "water"
        numbers[key] = {"mobility_ratio": m, "breakthrough_pv": bt, "recovery_end": float(ds.recovery[-1]),
                        "recovery_at_breakthrough": float(ds.recovery.sel(pv=bt)) if np.isfinite(bt) else None,
                        "n_steps": ds.attrs["n_steps"], "n_pressure_solves": ds.attrs["n_pressure_solves"],
                        "wall_time_s": wall,
                        "max_mass_balance_error": max(v for k, v in ds.attrs.items() if k.startswith("mass_bal"))}
        for j, t in enumerate(ds.profile_pv.values):
            axm = fig.add_subplot(grid[j + 1, 1 if polymer else 0])
            im = axm.imshow(ds.sw.isel(profile_pv=j).values, origin="lower", extent=extent, cmap="jet",
                            vmin=params["SWI"], vmax=1.0 - 0.3, aspect="auto")
            if polymer:  # the polymer front: half the injected concentration
                cp = ds.c_polymer.isel(profile_pv=j).values
                axm.contour(ds.x.values, ds.y.values, cp, levels=[0.5 * cp.max()], colors="white", linewidths=0.8)
            axm.set_title(f"{label}: S_w at {t:.2f} PV" + (" (white: polymer front)" if polymer else ""),
                          fontsize=9)
            axm.set_xlabel("x / L", fontsize=8)
            axm.set_ylabel("y / L", fontsize=8)
    ax.set_xlabel("injected PV", fontsize=8)
    ax.set_ylabel("recovery (solid)\nwater cut (dashed)", fontsize=8)
    ax.set_title("recovery and water cut; dotted: water breakthrough", fontsize=9)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, loc="lower right")  # below the recovery curves, right of the breakthrough markers
    fig.colorbar(im, cax=fig.add_subplot(grid[1:, 2]), label="S_w")
    fig.suptitle("Viscous fingering (thesis Fig. 1.9): water flood M = 2.5 vs polymer flood M = 0.5", fontsize=10)
    fig.tight_layout()
    args.out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(args.out, dpi=130)
    plt.close(fig)
    args.out.with_suffix(".json").write_text(json.dumps(numbers, indent=2) + "\n")
    print(json.dumps(numbers, indent=2))
    return args.out


if __name__ == "__main__":
    print(main())
