"""2-D forward-model benchmark (a script, not a test): ``python benchmarks/bench_two_d.py [--nx 400 --ny 80]``.

Runs the thesis sec. 1.8 water flood (M = 2.5, ``two_d.fingering_case``) on the 400 x 80 heterogeneous core to 1 PV
and reports wall and CPU time, time steps, pressure solves and peak memory (tracemalloc peak of the Python side,
which holds every 2-D array here, and the process's peak resident set). Target: <= 5 minutes on one core.

Baseline, measured in the same run: the 1-D model on the same case with ``nx`` cells, times ``ny`` (the cost of
``ny`` independent 1-D cores with the 2-D grid's cells); the ratio says what the 2-D pressure solve, the y fluxes and
the Python-driven time loop cost on top. Also timed: one pressure factor+solve on the final mobility, to state the
cost of solving the pressure at every step (``--pressure-every 1``) from the measured numbers.
"""

from __future__ import annotations

import argparse
import os
import resource
import time
import tracemalloc

import numpy as np

os.environ.setdefault("NUMBA_NUM_THREADS", "1")

from spflow.plugins.forward import state_layout as L  # noqa: E402
from spflow.plugins.forward.simulate import simulate  # noqa: E402
from spflow.plugins.forward.two_d import permeability_field  # noqa: E402
from spflow.plugins.forward.two_d.fingering_case import (  # noqa: E402
    fingering_effects, fingering_params, fingering_schedule)
from spflow.plugins.forward.two_d.grid2d import Grid2D  # noqa: E402
from spflow.plugins.forward.two_d.pressure2d import PressureSolver  # noqa: E402


def _timed(func):
    w, c = time.perf_counter(), time.process_time()
    out = func()
    return out, time.perf_counter() - w, time.process_time() - c


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--nx", type=int, default=400)
    parser.add_argument("--ny", type=int, default=80)
    parser.add_argument("--pv", type=float, default=1.0)
    parser.add_argument("--pressure-every", type=int, default=10)
    args = parser.parse_args(argv)
    nx, ny = args.nx, args.ny
    params, effects, schedule = fingering_params(), fingering_effects(), fingering_schedule(False, args.pv)
    perm = permeability_field(nx, ny, seed=1)

    # warm-up (numba cache load / compile) on a small grid
    simulate(schedule, params, cells=(10, 3), effects=effects, pv_step=0.1)
    simulate(schedule, params, cells=10, effects=effects, pv_step=0.1)

    one, w1, c1 = _timed(lambda: simulate(schedule, params, cells=nx, effects=effects, pv_step=0.01))
    tracemalloc.start()
    two, w2, c2 = _timed(lambda: simulate(schedule, params, cells=(nx, ny), permeability=perm, effects=effects,
                                          pv_step=0.01, pressure_every=args.pressure_every))
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    rss_mb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0

    # one pressure factor + solve at this size (mean of 5), for the every-step IMPES estimate
    solver = PressureSolver(Grid2D(nx, ny, two.attrs["aspect"], perm.values / params.get("PERM", 700.0)))
    mobility = np.full((ny, nx), 0.8 / 20e-3)
    _, wp, _ = _timed(lambda: [solver.solve(mobility) for _ in range(5)])
    wp /= 5
    steps, solves = two.attrs["n_steps"], two.attrs["n_pressure_solves"]
    every_step = w2 + (steps - solves) * wp

    print(f"load average (1, 5, 15 min): {os.getloadavg()}")
    print(f"{'run':44s} {'wall s':>9s} {'cpu s':>9s} {'steps':>7s} {'p-solves':>9s} {'ratio':>8s}")
    base = w1 * ny
    print(f"{f'1-D, {nx} cells (baseline x {ny} = {base:.1f} s)':44s} {w1:9.2f} {c1:9.2f} "
          f"{one.attrs['n_steps']:7d} {'-':>9s} {1.0 / ny:8.3f}")
    print(f"{f'2-D {nx} x {ny}, pressure every {args.pressure_every} steps':44s} {w2:9.2f} {c2:9.2f} "
          f"{steps:7d} {solves:9d} {w2 / base:8.3f}")
    print(f"{'2-D, pressure every step (estimate)':44s} {every_step:9.2f} {'-':>9s} {steps:7d} {steps:9d} "
          f"{every_step / base:8.3f}")
    print(f"one pressure factor+solve: {wp * 1e3:.1f} ms; 2-D per step: {w2 / steps * 1e3:.1f} ms")
    print(f"peak memory: tracemalloc {peak / 2**20:.1f} MiB, max RSS {rss_mb:.0f} MiB; "
          f"state+properties arrays {(L.NST + L.NPR) * nx * ny * 8 / 2**20:.1f} MiB")
    print(f"recovery at {args.pv:g} PV: 1-D {float(one.recovery[-1]):.4f}, 2-D {float(two.recovery[-1]):.4f}; "
          f"max mass-balance error {max(v for k, v in two.attrs.items() if k.startswith('mass_bal')):.1e}")
    print(f"target <= 300 s on one core: {'met' if w2 <= 300.0 else 'NOT met'} ({w2:.0f} s wall)")


if __name__ == "__main__":
    main()
