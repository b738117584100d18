"""Forward-model benchmark (a script, not a test): ``python benchmarks/bench_forward.py [--runs 1000]``.

Measures, for BCF1 at 100 cells with full physics (all default effects):

1. median wall time per run on one core after warm-up (target <= 20 ms);
2. wall time of 1000 runs on 2 cores with joblib/loky, parameters drawn from the thesis's Table 3.2 prior
   (target <= 15 s), after the workers have loaded the compiled kernel;
3. peak memory per run: tracemalloc peak of the Python side, plus the kernel's own arrays (numba allocates them
   outside tracemalloc's view; their size is computed from the layout);
4. the ratio to a first-order, vectorised-over-cells pure-numpy IMPES loop measured in the same process.

Next to the wall times it reports CPU times (this thread's for the single runs, the workers' summed over the 1000
runs): on a machine shared with other jobs the wall times grow with the load, the CPU times hardly; the load
average is printed with the table.

Baseline choice: re-implementing the full SP physics in numpy would duplicate every sub-model, so the baseline is
the two-phase subset both codes share exactly -- Corey/Buckley-Leverett waterflood (capillary desaturation,
dispersion, Pc off), upwind fluxes, the same grid, CFL number, schedule length (4.23 PV) and output grid -- timed
against ``simulate`` on the same subset. Both are also checked to agree on recovery.
"""

from __future__ import annotations

import argparse
import os
import statistics
import time
import tracemalloc

import numpy as np

os.environ.setdefault("NUMBA_NUM_THREADS", "1")

from joblib import Parallel, delayed  # noqa: E402

from spflow.plugins.forward import kernel as KR  # noqa: E402
from spflow.plugins.forward import output_records as R  # noqa: E402
from spflow.plugins.forward import state_layout as SL  # noqa: E402
from spflow.plugins.forward import transport as TR  # noqa: E402
from spflow.plugins.forward.parameters import default_params  # noqa: E402
from spflow.plugins.forward.simulate import simulate  # noqa: E402

CELLS = 100
BL_PARAMS = {"SWI": 0.2, "S1RWC": 0.2, "S2RWC": 0.3, "P1RWC": 0.1, "P2RWC": 0.8, "E1WC": 2.0, "E2WC": 2.0,
             "VIS1": 1.0, "VIS2": 13.8}
BL_EFFECTS = {"capillary_desaturation": 0.0, "dispersion": 0.0, "capillary_pressure": 0.0}
WATER_423 = [{"pv": 4.23, "salinity_ppm": 9400.0}]
PRIOR = {"ALPHAV2": (0.0, 3.0), "HBNC70": (0.02, 0.05), "HBNC71": (0.01, 0.02), "AD31": (0.0, 2.0),
         "GAMHF": (55.0, 100.0), "CRK": (0.05, 0.1), "E1WC": (1.5, 3.0), "E2WC": (1.5, 3.0),
         "ALPHAL1": (0.008, 0.012)}  # thesis Table 3.2


def numpy_waterflood(cells: int, total_pv: float, pv_step: float, cfl: float, p: dict) -> tuple[np.ndarray, int]:
    """First-order upwind Buckley-Leverett IMPES, vectorised over cells; returns (recovery on the pv grid, steps)."""
    swc, sor, krw0, kro0, nw, no = p["S1RWC"], p["S2RWC"], p["P1RWC"], p["P2RWC"], p["E1WC"], p["E2WC"]
    muw, muo = p["VIS1"], p["VIS2"]
    window = 1.0 - swc - sor
    s = np.full(cells, p["SWI"])
    dx = 1.0 / cells
    grid = np.arange(int(round(total_pv / pv_step)) + 1) * pv_step
    rec = np.zeros(grid.size)
    ooip = 1.0 - p["SWI"]
    t, produced, k, steps = 0.0, 0.0, 1, 0
    flux = np.empty(cells + 1)
    while k < grid.size:
        sn = np.clip((s - swc) / window, 0.0, 1.0)
        lw = krw0 * sn**nw / muw
        lo = kro0 * (1.0 - sn) ** no / muo
        lt = lw + lo
        f = lw / lt
        inner = (sn > 0.0) & (sn < 1.0)
        dlw = np.where(inner, nw * lw / np.where(inner, sn, 1.0) / window, 0.0)
        dlo = np.where(inner, no * lo / np.where(inner, 1.0 - sn, 1.0) / window, 0.0)
        # same CFL bound as the kernel: df/dS and the phase velocities f/S
        speed = np.maximum((dlw * lo + lw * dlo) / lt**2, np.maximum(f / s, (1.0 - f) / (1.0 - s)))
        dt = min(cfl * dx / speed.max(), grid[k] - t)
        flux[0] = 1.0
        flux[1:] = f
        s = s - dt / dx * np.diff(flux)
        produced += (1.0 - f[-1]) * dt
        t += dt
        steps += 1
        if t >= grid[k] - 1e-14:
            t = grid[k]
            rec[k] = produced / ooip
            k += 1
    return rec, steps


def kernel_array_bytes(cells: int, n_out: int) -> int:
    """Bytes of the arrays the compiled kernel allocates (state, properties, fluxes, scratch, outputs)."""
    # + new[6], six dispersion work arrays of N_DISP rows, the pressure profile
    per_cell = SL.NST + SL.NPR + TR.NFLUX + 6 + 6 * KR.N_DISP + 1
    return 8 * (cells * per_cell + TR.NFLUX + KR.N_DISP + R.N_SERIES * n_out + 4 * 6 + KR.N_INFO + 6)


def _prior_draw(seed: int) -> dict:
    rng = np.random.default_rng(seed)
    p = {name: float(rng.uniform(lo, hi)) for name, (lo, hi) in PRIOR.items()}
    p["E1C"] = p["E2C"] = float(rng.uniform(1.5, 3.0))
    return p


def _one_run(seed: int) -> tuple[float, float]:
    """Final recovery of one prior draw and the CPU time the run took in its worker (s)."""
    start = time.thread_time()
    ds = simulate("BCF1", _prior_draw(seed), cells=CELLS)
    return float(ds.recovery.values[-1]), time.thread_time() - start


def _median_ms(func, repeats: int) -> tuple[float, float]:
    """Median wall time and median CPU time of this thread (ms); the CPU time is insensitive to other processes
    competing for the cores (a shared machine)."""
    wall, cpu = [], []
    for _ in range(repeats):
        start, start_cpu = time.perf_counter(), time.thread_time()
        func()
        wall.append(time.perf_counter() - start)
        cpu.append(time.thread_time() - start_cpu)
    return 1e3 * statistics.median(wall), 1e3 * statistics.median(cpu)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=1000, help="runs for the 2-core throughput test")
    parser.add_argument("--repeats", type=int, default=30, help="repeats for the single-run median")
    args = parser.parse_args()

    start = time.perf_counter()
    ds = simulate("BCF1", cells=CELLS)  # compile or load the cached kernel
    first = time.perf_counter() - start
    full_ms, full_cpu_ms = _median_ms(lambda: simulate("BCF1", cells=CELLS), args.repeats)
    ds = simulate("BCF1", cells=CELLS)
    kernel_ms = ds.attrs["wall_time_s"] * 1e3

    tracemalloc.start()
    simulate("BCF1", cells=CELLS)
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    kernel_bytes = kernel_array_bytes(CELLS, ds.sizes["pv"])

    bl_ds = simulate(WATER_423, BL_PARAMS, cells=CELLS, effects=BL_EFFECTS, scheme="upwind")
    ours_bl_ms, ours_bl_cpu = _median_ms(lambda: simulate(WATER_423, BL_PARAMS, cells=CELLS, effects=BL_EFFECTS,
                                                          scheme="upwind"), args.repeats)
    p = default_params() | BL_PARAMS
    rec_np, steps_np = numpy_waterflood(CELLS, 4.23, 0.01, 0.5, p)
    numpy_ms, numpy_cpu = _median_ms(lambda: numpy_waterflood(CELLS, 4.23, 0.01, 0.5, p), max(3, args.repeats // 5))
    agree = float(np.max(np.abs(rec_np - bl_ds.recovery.values)))

    with Parallel(n_jobs=2, backend="loky") as pool:
        pool(delayed(_one_run)(s) for s in range(4))  # workers import and load the cached kernel
        start = time.perf_counter()
        results = pool(delayed(_one_run)(s) for s in range(args.runs))
        par_s = time.perf_counter() - start
    recs = [r for r, _ in results]
    par_cpu_s = sum(c for _, c in results)

    rows = [
        ("first call (compile or cache load)", f"{first:.2f} s", ""),
        ("BCF1, 100 cells, full physics: median per run (1 core)", f"{full_ms:.1f} ms", "target <= 20 ms"),
        ("  median CPU time per run (this thread)", f"{full_cpu_ms:.1f} ms", "load-independent"),
        ("  of which compiled kernel", f"{kernel_ms:.1f} ms", f"{ds.attrs['n_steps']} steps"),
        (f"{args.runs} BCF1 runs, prior draws, 2 cores (loky)", f"{par_s:.2f} s", "target <= 15 s"),
        ("  worker CPU time / 2 (wall time on 2 idle cores)", f"{par_cpu_s / 2:.2f} s",
         f"mean {1e3 * par_cpu_s / args.runs:.1f} ms per run"),
        ("  recovery range over the draws", f"{min(recs):.3f} - {max(recs):.3f}", ""),
        ("peak memory per run: tracemalloc (Python side)", f"{peak / 1e6:.2f} MB", ""),
        ("peak memory per run: kernel arrays (numba NRT)", f"{kernel_bytes / 1e6:.3f} MB", ""),
        ("waterflood subset, simulate (upwind)", f"{ours_bl_ms:.2f} ms", f"{bl_ds.attrs['n_steps']} steps"),
        ("waterflood subset, pure-numpy first-order loop", f"{numpy_ms:.1f} ms", f"{steps_np} steps"),
        ("  speed-up over numpy baseline (wall)", f"{numpy_ms / ours_bl_ms:.1f} x", f"max |dRF| = {agree:.1e}"),
        ("  speed-up over numpy baseline (CPU time)", f"{numpy_cpu / ours_bl_cpu:.1f} x", ""),
    ]
    width = max(len(r[0]) for r in rows)
    print(f"load average at the end (1, 5, 15 min): {', '.join(f'{x:.1f}' for x in os.getloadavg())}"
          f" on {os.cpu_count()} CPUs")
    print(f"{'quantity':<{width}}  {'value':>14}  note")
    print("-" * (width + 40))
    for name, value, note in rows:
        print(f"{name:<{width}}  {value:>14}  {note}")


if __name__ == "__main__":
    main()
