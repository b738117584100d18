"""Implicit vs explicit capillary flux on ordinary runs (a script, not a test): ``python benchmarks/bench_capillary.py``.

For BCF1-3 at several strengths of the ``capillary_pressure`` effect (entry pressure ``s * CPC0``, the other
parameters and effects at their defaults) and several grids, runs ``simulate`` with ``capillary="explicit"`` (the
forward-Euler flux at its own diffusion-limited step) and ``capillary="implicit"`` (the linearly implicit step) and
reports, per case, the largest differences of the series on the 0.1 PV output grid -- recovery and oil cut (an
interval average) in absolute terms, dp relative to the explicit run's -- next to the tolerance of the output-grid
test of issue 20 (``tests/forward/test_output_grid_independence.py``: 1e-3, 1e-3, 0.5 %), and the steps and CPU
times of both. ``--early`` also reports dp from 0.15 PV on only (the inlet transient into connate water).
"""

from __future__ import annotations

import argparse
import os
import time

import numpy as np

os.environ.setdefault("NUMBA_NUM_THREADS", "1")

from spflow.plugins.forward.simulate import simulate  # noqa: E402

TOL_RECOVERY, TOL_CUT, TOL_DP = 1.0e-3, 1.0e-3, 5.0e-3


def run(schedule: str, strength: float, cells: int, capillary: str):
    cpu = time.process_time()
    ds = simulate(schedule, cells=cells, effects={"capillary_pressure": strength}, pv_step=0.1, capillary=capillary,
                  max_steps=10**9, max_wall_s=3600.0)
    return ds, time.process_time() - cpu


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--schedules", default="BCF1,BCF2,BCF3")
    parser.add_argument("--strengths", default="0.3,1,3")
    parser.add_argument("--cells", default="30,60,100")
    args = parser.parse_args()
    simulate("BCF1", cells=30, effects={"capillary_pressure": 1.0}, capillary="implicit")  # compile / load
    print(f"load average {os.getloadavg()[0]:.1f}; tolerance: recovery {TOL_RECOVERY:g}, oil cut {TOL_CUT:g} (abs), "
          f"dp {TOL_DP:.1%} (rel)")
    print("schedule strength cells | max|d recovery| max|d oil cut| max|d dp|/dp (all, >= 0.15 PV) at PV | "
          "steps expl impl | CPU s expl impl | within")
    worst = np.zeros(3)
    for schedule in args.schedules.split(","):
        for strength in (float(s) for s in args.strengths.split(",")):
            for cells in (int(c) for c in args.cells.split(",")):
                exp, t_exp = run(schedule, strength, cells, "explicit")
                imp, t_imp = run(schedule, strength, cells, "implicit")
                d_rec = float(np.max(np.abs(imp.recovery.values - exp.recovery.values)))
                d_cut = float(np.max(np.abs(imp.oil_cut.values - exp.oil_cut.values)))
                rel = np.abs(imp.dp.values / exp.dp.values - 1.0)
                k = int(np.argmax(rel))
                late = exp.pv.values >= 0.15
                d_dp_late = float(np.max(rel[late]))
                ok = d_rec <= TOL_RECOVERY and d_cut <= TOL_CUT and rel[k] <= TOL_DP
                worst = np.maximum(worst, [d_rec, d_cut, rel[k]])
                print(f"{schedule} {strength:4g} {cells:4d} | {d_rec:.2e} {d_cut:.2e} {rel[k]:.2e} {d_dp_late:.2e} "
                      f"at {exp.pv.values[k]:.2f} | {exp.attrs['n_steps']:7d} {imp.attrs['n_steps']:6d} | "
                      f"{t_exp:7.2f} {t_imp:6.2f} | {'yes' if ok else 'NO'}", flush=True)
    print(f"worst: recovery {worst[0]:.2e}, oil cut {worst[1]:.2e}, dp {worst[2]:.2e}")


if __name__ == "__main__":
    main()
