"""Reproduce thesis Figs. 3.3-3.5 and 3.7-3.9: the PCE proxy of BCF1 over the 9 parameters of Table 3.2.

The simulator runs go through an spflow pipeline (``parameter_space`` -> ``lhs_design`` -> ``forward``, cached in
``--cache``): nested training designs made of LHS batches (50, +50, +100, +300 by default, so N_s = 50, 100, 200,
500) and one independent LHS validation set (``--validation`` runs; the thesis uses 10^4). For every N_s the ``pce``
stage fits dp and recovery (0.1 PV series, p <= 5, q = 0.9) with OLS and with hybrid LARS, and the
``surrogate_validation`` stage scores it on the validation set. Writes to ``docs/figures`` (Figs. 3.3, 3.4 and 3.8
drawn by :mod:`spflow.plugins.surrogates.figures`):

* ``fig_3_3_pce_loo.png``: ε_LOO^mean and ε_emp^mean per QoI against N_s (Fig. 3.3);
* ``fig_3_4_pce_scatter.png``: proxy vs simulator at three N_s, every PV step and max Δp / final recovery
  (Figs. 3.4-3.5);
* ``fig_3_7_pce_moment_errors.png``: relative L2 errors (Eq. 3.15) of the mean and variance curves (Fig. 3.7);
* ``fig_3_8_pce_moments.png``: mean ± std over PV, PCE (Eqs. 3.11-3.12) vs the validation runs (Figs. 3.8-3.9);

and prints the numbers. Run: ``.venv/bin/python benchmarks/figures/fig_3_pce.py [--validation 1000] [--jobs 2]``.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import xarray as xr  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]

import spflow  # noqa: E402
from spflow.plugins.design.thesis_tables import TABLE_3_2  # noqa: E402
from spflow.core.stage import StageContext  # noqa: E402
from spflow.plugins.surrogates.figure_data import error_history  # noqa: E402
from spflow.plugins.surrogates.figures import (convergence_figure, moments_figure,  # noqa: E402
                                               proxy_vs_simulator_figure)
from spflow.plugins.surrogates.pce_stage import PCEStage  # noqa: E402
from spflow.plugins.surrogates.validation import SurrogateValidation  # noqa: E402

SOLVERS = ("ols", "lars")


def simulations(batches: list[int], n_validation: int, cells: int, cache: Path, jobs: int):
    """(space, training design, training responses, validation design, validation responses)."""
    p = spflow.Pipeline("fig_3_pce")
    p.add("space", "parameter_space", params={"names": list(TABLE_3_2), "ranges": TABLE_3_2})
    forward = {"experiments": ["BCF1"], "cells": cells, "pv_step": 0.1}
    for k, size in enumerate(batches):
        p.add(f"design{k}", "lhs_design", inputs={"space": "space"}, params={"samples": size, "seed": 100 + k})
        p.add(f"runs{k}", "forward", inputs={"design": f"design{k}"}, params=forward)
    p.add("design_val", "lhs_design", inputs={"space": "space"}, params={"samples": n_validation, "seed": 999})
    p.add("runs_val", "forward", inputs={"design": "design_val"}, params=forward)
    result = spflow.run(p, cache=cache, jobs=jobs)

    def stack(name):
        ds = xr.concat([result[f"{name}{k}"] for k in range(len(batches))], dim="sample",
                       data_vars="minimal", coords="minimal", compat="override")
        return ds.assign_coords(sample=np.arange(ds.sizes["sample"]))

    return result["space"], stack("design"), stack("runs"), result["design_val"], result["runs_val"]


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--batches", type=int, nargs="+", default=[50, 50, 100, 300])
    parser.add_argument("--validation", type=int, default=1000)
    parser.add_argument("--cells", type=int, default=100)
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--cache", type=Path, default=ROOT / ".spflow")
    parser.add_argument("--out", type=Path, default=ROOT / "docs" / "figures")
    args = parser.parse_args(argv)

    space, design, runs, design_val, runs_val = simulations(args.batches, args.validation, args.cells, args.cache,
                                                            args.jobs)
    sizes = np.cumsum(args.batches)
    ctx = StageContext(node="fig_3_pce", n_jobs=args.jobs, verbose=False)
    fits, checks = {}, {}
    for solver in SOLVERS:
        for n in sizes:
            sub = {"design": design.isel(sample=slice(0, n)), "responses": runs.isel(sample=slice(0, n))}
            fits[solver, n] = PCEStage(solver=solver).run(ctx, space=space, **sub)
            checks[solver, n] = SurrogateValidation().run(ctx, surrogate=fits[solver, n], design=design_val,
                                                          responses=runs_val)
    history = {solver.upper(): error_history([fits[solver, n] for n in sizes]) for solver in SOLVERS}

    print(f"BCF1, Table 3.2 space, {args.cells} cells; validation: {args.validation} LHS runs")
    print(f"{'solver':<6}{'N_s':>5}{'p':>3}  {'LOO dp':>9}{'LOO rec':>9}{'emp dp':>9}{'emp rec':>9}"
          f"{'R2 maxdp':>10}{'R2 final rec':>13}{'L2 mean dp':>11}{'L2 var dp':>10}{'L2 var rec':>11}")
    for (solver, n), ds in fits.items():
        h, v = history[solver.upper()].sel(n_s=n), checks[solver, n]
        qoi = {str(name): i for i, name in enumerate(v["qoi_variable"].values)}
        print(f"{solver:<6}{n:>5}{ds.attrs['degree']:>3}  {float(h['loo'].sel(variable='dp')):>9.2e}"
              f"{float(h['loo'].sel(variable='recovery')):>9.2e}{float(h['empirical'].sel(variable='dp')):>9.2e}"
              f"{float(h['empirical'].sel(variable='recovery')):>9.2e}{float(v['r2_max'][qoi['dp']]):>10.4f}"
              f"{float(v['r2_final'][qoi['recovery']]):>13.4f}{float(v['mean_l2_error'][qoi['dp']]):>11.2e}"
              f"{float(v['variance_l2_error'][qoi['dp']]):>10.2e}"
              f"{float(v['variance_l2_error'][qoi['recovery']]):>11.2e}")

    args.out.mkdir(parents=True, exist_ok=True)
    convergence_figure(history, args.out / "fig_3_3_pce_loo.png")
    shown = dict.fromkeys([sizes[0], sizes[min(2, len(sizes) - 1)], sizes[-1]])
    proxy_vs_simulator_figure({f"PCE (OLS), N_s = {n}": fits["ols", n] for n in shown}, design_val, runs_val,
                              args.out / "fig_3_4_pce_scatter.png")
    moments_figure({f"PCE (OLS), N_s = {n}": fits["ols", n] for n in dict.fromkeys([sizes[0], sizes[-1]])},
                   runs_val, args.out / "fig_3_8_pce_moments.png")

    # Fig. 3.7: relative L2 errors of mean and variance curves against N_s (from the surrogate_validation outputs)
    fig, axes = plt.subplots(1, 2, figsize=(10, 3.8), sharey=True)
    for ax, what in zip(axes, ("mean_l2_error", "variance_l2_error")):
        for solver, style in zip(SOLVERS, ("-", "--")):
            for name, colour in zip(("dp", "recovery"), ("tab:red", "tab:green")):
                values = []
                for n in sizes:
                    v = checks[solver, n]
                    values.append(float(v[what][list(v["qoi_variable"].values).index(name)]))
                ax.semilogy(sizes, values, "o" + style, color=colour, label=f"{name} ({solver.upper()})")
        ax.axhline(2.5e-2, color="k", lw=0.8, ls=":", label="2.5e-2 (thesis threshold)")
        ax.set_title("mean" if what.startswith("mean") else "variance")
        ax.set_xlabel("training runs N_s")
        ax.grid(alpha=0.3, which="both")
    axes[0].set_ylabel("relative L2 error (Eq. 3.15)")
    axes[0].legend(fontsize=8)
    fig.suptitle(f"PCE moments vs {args.validation} LHS runs (cf. thesis Fig. 3.7)")
    fig.tight_layout()
    fig.savefig(args.out / "fig_3_7_pce_moment_errors.png", dpi=110)
    plt.close(fig)
    print(f"wrote {', '.join(f.name for f in sorted(args.out.glob('fig_3_[3478]_pce*.png')))} to {args.out}")


if __name__ == "__main__":
    main()
