"""Reproduce thesis Fig. 1.7: simulated vs analytic Buckley-Leverett saturation profiles for mu_o/mu_w = 0.5, 1, 2.

Corey k_r° = 1, n = 2, no residuals (thesis Fig. 1.6), 200 cells as in the thesis, TVD scheme; the profile is taken
at a common injected volume (0.5 PV; the thesis plots "after one day"). The analytic curves come from the
independent oracle in ``tests/oracles``. Writes ``docs/figures/fig_1_7_buckley_leverett.png``.

Run: ``.venv/bin/python benchmarks/figures/fig_1_7_buckley_leverett.py [--cells N] [--pv T] [--out PATH]``.
"""

import argparse
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "tests"))
sys.path.insert(0, str(ROOT))

from oracles import CoreyFractionalFlow, buckley_leverett, corey_params  # noqa: E402
from spflow.plugins.forward.simulate import simulate  # noqa: E402

VISCOSITY_RATIOS = (0.5, 1.0, 2.0)
COLOURS = ("tab:blue", "tab:orange", "tab:green")


def main(argv=None) -> Path:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cells", type=int, default=200)
    parser.add_argument("--pv", type=float, default=0.5, help="injected pore volumes at which profiles are drawn")
    parser.add_argument("--out", type=Path, default=ROOT / "docs" / "figures" / "fig_1_7_buckley_leverett.png")
    args = parser.parse_args(argv)

    fig, ax = plt.subplots(figsize=(6.4, 4.2))
    x_exact = np.linspace(0.0, 1.0, 2001)
    for ratio, colour in zip(VISCOSITY_RATIOS, COLOURS):
        flux = CoreyFractionalFlow(mu_o=ratio)
        ds = simulate(
            [{"pv": args.pv, "salinity_ppm": 9400.0}],
            corey_params(flux),
            cells=args.cells,
            effects={"capillary_desaturation": 0.0, "dispersion": 0.0, "capillary_pressure": 0.0},
            scheme="tvd",
            profiles_at=[args.pv],
        )
        t_d = float(ds["profile_pv"][0])
        ax.plot(x_exact, buckley_leverett(flux).profile(x_exact, t_d), color=colour, lw=1.5,
                label=rf"analytic, $\mu_r$ = {ratio:g}")
        ax.plot(ds["x"], ds["sw"].isel(profile_pv=0), "o", color=colour, ms=2.5, mfc="none",
                label=rf"spflow TVD, $\mu_r$ = {ratio:g}")
    ax.set_xlabel(r"dimensionless distance $x_D = x/L$")
    ax.set_ylabel(r"water saturation $S_w$")
    ax.set_title(f"Buckley-Leverett validation ({args.cells} cells, {args.pv:g} PV injected)")
    ax.set_xlim(0.0, 1.0)
    ax.set_ylim(-0.02, 1.02)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, ncol=2, loc="lower left")
    fig.tight_layout()
    args.out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(args.out, dpi=150)
    plt.close(fig)
    return args.out


if __name__ == "__main__":
    print(main())
