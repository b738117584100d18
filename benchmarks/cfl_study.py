"""Courant-number study of the TVD transport step (a script, not a test): ``python benchmarks/cfl_study.py``.

The public ``simulate`` caps the TVD Courant number at 0.5, the bound under which the flux-limited update is TVD
whatever Lax-Wendroff factor the limiter uses (``transport`` module docstring). The step count -- and so the run
time -- is inversely proportional to it, so this script measures what a larger Courant number would buy and cost:
BCF1-3 (defaults, full physics) at 100 and 200 cells for Courant numbers 0.5 ... 1.0, calling the compiled kernel
directly (past the public bound), against a converged reference at 800 cells and Courant number 0.5.

Columns: steps, kernel CPU time, and the errors against the reference -- relative RMS of the pressure drop, max
|recovery| difference (fraction of OOIP), RMS oil cut, RMS effluent polymer relative to its maximum -- plus the worst
per-component mass-balance residual (PV). A scheme that loses the waterflood's rarefaction shows up as a recovery
error of order 0.1 (a piston-like front).
"""

from __future__ import annotations

import argparse
import os
import time

import numpy as np

os.environ.setdefault("NUMBA_NUM_THREADS", "1")

from spflow.plugins.forward.kernel import run_kernel  # noqa: E402
from spflow.plugins.forward.run_arguments import validate_run  # noqa: E402
from spflow.plugins.forward.simulate import kernel_arguments  # noqa: E402

SCHEDULES = ("BCF1", "BCF2", "BCF3")


def run(schedule: str, cells: int, courant: float) -> tuple[np.ndarray, int, float, float]:
    """``(series, steps, kernel CPU seconds, worst mass-balance residual)`` of one TVD run at any Courant number."""
    sched, resolved, strengths, _, cells, pv_step, prof, _ = validate_run(schedule, None, cells, None, "tvd", 0.01,
                                                                       None, 0.5)
    prm, end_pv, inj, flow, out_pv = kernel_arguments(sched, resolved, strengths, pv_step)
    start = time.process_time()
    status, info, steps, series, _, totals, _ = run_kernel(prm, end_pv, inj, flow, out_pv, prof, cells, True, courant,
                                                           2**62, np.zeros(1, dtype=np.int64))
    cpu = time.process_time() - start
    if status != 0:
        raise RuntimeError(f"{schedule} at {cells} cells, Courant {courant}: kernel status {status}, info {info}")
    balance = float(np.max(np.abs(totals[3] - totals[0] - totals[1] + totals[2])))
    return series, int(steps), cpu, balance


def errors(series: np.ndarray, ref: np.ndarray) -> tuple[float, float, float, float]:
    """Relative RMS dp, max |recovery|, RMS oil cut, RMS effluent polymer / its maximum (series rows of ``kernel``)."""
    dp = np.sqrt(np.mean((series[0] - ref[0]) ** 2) / np.mean(ref[0] ** 2))
    rec = np.max(np.abs(series[2] - ref[2]))
    cut = np.sqrt(np.mean((series[1] - ref[1]) ** 2))
    cp = np.sqrt(np.mean((series[3] - ref[3]) ** 2)) / np.max(ref[3])
    return float(dp), float(rec), float(cut), float(cp)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--courant", type=float, nargs="+", default=[0.5, 0.6, 0.7, 0.8, 0.9, 1.0])
    parser.add_argument("--cells", type=int, nargs="+", default=[100, 200])
    parser.add_argument("--ref-cells", type=int, default=800)
    args = parser.parse_args()
    run("BCF1", 20, 0.5)  # compile / load the cached kernel
    refs = {s: run(s, args.ref_cells, 0.5)[0] for s in SCHEDULES}
    print(f"reference: {args.ref_cells} cells, Courant 0.5")
    print(f"{'sched':5s} {'cells':>5s} {'C':>4s} {'steps':>6s} {'cpu ms':>7s} {'ratio':>6s} {'dp rel':>7s} "
          f"{'rec':>7s} {'cut':>7s} {'cp rel':>7s} {'balance':>8s}")
    for s in SCHEDULES:
        for cells in args.cells:
            base = None
            for c in args.courant:
                series, steps, cpu, balance = min((run(s, cells, c) for _ in range(3)), key=lambda r: r[2])
                base = cpu if base is None else base
                dp, rec, cut, cp = errors(series, refs[s])
                print(f"{s:5s} {cells:5d} {c:4.2f} {steps:6d} {cpu * 1e3:7.1f} {cpu / base:6.2f} {dp:7.4f} "
                      f"{rec:7.4f} {cut:7.4f} {cp:7.4f} {balance:8.1e}", flush=True)


if __name__ == "__main__":
    main()
