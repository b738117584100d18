"""PCE evaluation benchmark (a script, not a test): ``python benchmarks/bench_pce.py [--points 10000] [--repeat 7]``.

The issue's case: a 9-D PCE with the thesis's truncation (p = 5, q = 0.9: 724 terms) for 43 outputs (one QoI on the
0.1 PV grid of BCF1), evaluated at 10 000 points; target <= 50 ms for ``PCE.predict`` (mean and variance).

Rows of the table (medians over ``--repeat`` runs, after one warm-up):

1. ``PCE.predict`` (blockwise Ψ by the parent-times-factor recurrence + one-thread BLAS matmul);
2. ``design_matrix`` alone (Ψ, 10 000 x 724);
3. baseline: chaospy's own evaluation of the same expansion, built the way ``chaospy.fit_regression`` returns it
   (``generate_expansion(5, Iid(Uniform(-1, 1), 9), normed=True, cross_truncation=0.9)`` times the coefficients,
   summed over terms) and called at the points — its agreement with ``PCE.predict`` is printed too;
4. one forward-model run, ``spflow.simulate("BCF1")`` with default settings (100 cells, 0.01 PV output grid).

Wall and CPU time are both printed: on a machine shared with other jobs the wall time includes waiting for a core.
"""

from __future__ import annotations

import argparse
import os
import statistics
import time

import chaospy
import numpoly
import numpy as np

import spflow
from spflow.plugins.surrogates.basis import design_matrix, multi_indices
from spflow.plugins.surrogates.outputs import OutputIndex
from spflow.plugins.surrogates.pce_model import PCE

D, P, Q, M = 9, 5, 0.9, 43


def median_time(func, repeat: int) -> tuple[float, float]:
    """Median wall time and median CPU time of this process (the CPU time is what the work costs on an idle core;
    on a busy machine the wall time also counts waiting for a core)."""
    func()
    wall, cpu = [], []
    for _ in range(repeat):
        start, start_cpu = time.perf_counter(), time.process_time()
        func()
        wall.append(time.perf_counter() - start)
        cpu.append(time.process_time() - start_cpu)
    return statistics.median(wall), statistics.median(cpu)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--points", type=int, default=10_000)
    parser.add_argument("--repeat", type=int, default=7)
    args = parser.parse_args()

    rng = np.random.default_rng(0)
    indices = multi_indices(D, P, Q)
    decay = 1.0 / (1.0 + indices.sum(axis=1)) ** 2
    coefficients = rng.normal(size=(M, indices.shape[0])) * decay
    outputs = OutputIndex(np.full(M, "dp"), np.full(M, "BCF1"), np.arange(M) * 0.1, {"dp": "Pa"})
    lower, upper = np.zeros(D), np.ones(D)
    zeros = np.zeros(M)
    model = PCE([f"x{k}" for k in range(D)], lower, upper, outputs, indices, coefficients, zeros, zeros, zeros,
                np.ones(M), {"degree": P, "q": Q, "solver": "ols", "n_train": 0})
    x = rng.uniform(lower, upper, (args.points, D))
    z = model.to_unit(x)

    t_predict = median_time(lambda: model.predict(x), args.repeat)
    t_psi = median_time(lambda: design_matrix(z, indices), args.repeat)

    expansion = chaospy.generate_expansion(P, chaospy.Iid(chaospy.Uniform(-1.0, 1.0), D), normed=True,
                                           cross_truncation=Q)
    polynomial = numpoly.sum(expansion * coefficients, axis=-1)
    t_chaospy = median_time(lambda: polynomial(*z.T), max(1, args.repeat // 3))
    difference = np.abs(np.asarray(polynomial(*z.T)).T - model.predict(x)[0]).max()

    spflow.simulate("BCF1")
    t_forward = median_time(lambda: spflow.simulate("BCF1"), max(1, args.repeat // 2))

    print(f"PCE: d = {D}, p = {P}, q = {Q}: {indices.shape[0]} terms, {M} outputs, {args.points} points "
          f"(load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} CPUs)")
    print(f"max |chaospy - PCE.predict| = {difference:.2e}")
    print(f"{'what':<42}{'wall [ms]':>11}{'CPU [ms]':>10}{'PCE.predict / this (wall)':>27}")
    rows = [("PCE.predict (mean + variance)", t_predict), ("design_matrix (Ψ only)", t_psi),
            ("chaospy expansion called at the points", t_chaospy), ("one forward run, simulate('BCF1')", t_forward)]
    for name, (wall, cpu) in rows:
        print(f"{name:<42}{1e3 * wall:>11.1f}{1e3 * cpu:>10.1f}{t_predict[0] / wall:>27.3g}")
    print(f"target PCE.predict <= 50 ms (wall): {'met' if t_predict[0] <= 0.05 else 'NOT met'}")


if __name__ == "__main__":
    main()
