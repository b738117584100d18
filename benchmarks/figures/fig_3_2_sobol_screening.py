"""Reproduce thesis Fig. 3.2: Sobol' screening of the 19 Table 3.1 parameters per sub-model on BCF1, total indices
for final oil recovery and maximum pressure drop, and compare the selection with the thesis's Table 3.2.

Runs the ``sobol_screening`` stage (per-group mode: each sub-model varied alone, the others at the Table 2.4
defaults; ranges from ``TABLE_3_1_RANGES``) on the ``parameter_space`` of ``table_3_1_names()``. The thesis ran
1000 simulations per sub-model; here N (d + 2) per sub-model of d parameters (N = 128: 384-896 runs, 4224 in all).
Prints the indices with their 95 % bootstrap half-widths, the selection and the thesis's choice, and writes
``docs/figures/fig_3_2_sobol_screening.png`` (and the result as netCDF with ``--netcdf``).

Run: ``.venv/bin/python benchmarks/figures/fig_3_2_sobol_screening.py [--samples N] [--cells C] [--jobs J]
[--mode per_group|joint] [--threshold T] [--top-k K] [--combine and|or] [--out PATH] [--netcdf PATH]``.
"""

import argparse
import time
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]

from spflow.plugins.design.thesis_tables import TABLE_3_2  # noqa: E402
from spflow.core.stage import StageContext  # noqa: E402
from spflow.plugins.design.parameter_space import ParameterSpace  # noqa: E402
from spflow.plugins.screening.figure import plot_total_indices  # noqa: E402
from spflow.plugins.screening.sobol_screening import SobolScreening  # noqa: E402
from spflow.plugins.screening.table_3_1 import TABLE_3_1, TABLE_3_1_RANGES, table_3_1_names  # noqa: E402


def main(argv=None) -> Path:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, default=128, help="Sobol' base sample size N (power of two)")
    parser.add_argument("--cells", type=int, default=100)
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--mode", choices=["per_group", "joint"], default="per_group")
    parser.add_argument("--threshold", type=float, default=0.1)
    parser.add_argument("--top-k", type=int, default=0)
    parser.add_argument("--combine", choices=["and", "or"], default="and")
    parser.add_argument("--out", type=Path, default=ROOT / "docs" / "figures" / "fig_3_2_sobol_screening.png")
    parser.add_argument("--netcdf", type=Path, default=None)
    args = parser.parse_args(argv)

    ctx = StageContext("sobol_screening", n_jobs=args.jobs, verbose=True)
    space = ParameterSpace(names=table_3_1_names(), ranges=TABLE_3_1_RANGES).run(ctx)
    stage = SobolScreening(samples=args.samples, cells=args.cells, experiments=["BCF1"], groups=TABLE_3_1,
                           mode=args.mode, threshold=args.threshold, top_k=args.top_k, combine=args.combine)
    start = time.perf_counter()
    result = stage.run(ctx, space=space)
    wall = time.perf_counter() - start
    if args.netcdf:
        result.to_netcdf(args.netcdf)

    qois = ["recovery_final:BCF1", "dp_max:BCF1"]
    print(f"\n{result.attrs['runs']} simulations ({args.mode}, N = {args.samples}, {args.cells} cells) "
          f"in {wall:.0f} s on {args.jobs} workers ({wall / result.attrs['runs'] * args.jobs * 1e3:.0f} ms per run)")
    print(f"selection: {result.attrs['selection_rule']} (score = max S_T over final recovery and max dp)\n")
    head = f"{'sub-model':28s} {'param':8s} {'range':>17s} {'S1 rec':>13s} {'ST rec':>13s} {'S1 dp':>13s} " \
           f"{'ST dp':>13s}  {'ours':4s} {'thesis':6s}"
    print(head)
    print("-" * len(head))
    for name in result["param"].values:
        row = result.sel(param=name)
        cells = []
        for qoi in qois:
            for k in ("S1", "ST"):
                cells.append(f"{float(row[k].sel(qoi=qoi)):6.3f}±{float(row[f'{k}_conf'].sel(qoi=qoi)):.3f}")
        rng = f"[{float(row['lower']):.4g}, {float(row['upper']):.4g}]"
        print(f"{str(row['group'].values):28s} {name:8s} {rng:>17s} {' '.join(f'{c:>13s}' for c in cells)}  "
              f"{'yes' if bool(row['selected']) else '-':4s} {'yes' if name in TABLE_3_2 else '-':6s}")
    st_conf = result["ST_conf"].sel(qoi=qois).values
    s1_conf = result["S1_conf"].sel(qoi=qois).values
    print(f"\n95 % CI half-width: S_T median {np.median(st_conf):.3f}, max {st_conf.max():.3f}; "
          f"S_1 median {np.median(s1_conf):.3f}, max {s1_conf.max():.3f}")
    ours = {str(n) for n in result["param"].values[result["selected"].values.astype(bool)]}
    print(f"selected {len(ours)}: {sorted(ours)}")
    print(f"thesis Table 3.2 ({len(TABLE_3_2)}): {sorted(TABLE_3_2)}")
    print(f"both: {sorted(ours & set(TABLE_3_2))}; only ours: {sorted(ours - set(TABLE_3_2))}; "
          f"only thesis: {sorted(set(TABLE_3_2) - ours)}")
    for group, members in TABLE_3_1.items():
        sub = result.sel(param=members, qoi=qois)
        print(f"  {group:28s} QoI std over its design: final recovery {np.sqrt(float(sub['variance'][0, 0])):.4f}, "
              f"max dp {np.sqrt(float(sub['variance'][1, 0])) / 1e3:.2f} kPa")

    fig = plot_total_indices(result, qois, title=f"Sobol' screening on BCF1 ({args.mode}, N = {args.samples}, "
                                                 f"{result.attrs['runs']} runs, {args.cells} cells)")
    args.out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(args.out, dpi=130)
    plt.close(fig)
    return args.out


if __name__ == "__main__":
    print(main())
