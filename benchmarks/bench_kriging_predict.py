"""What the Kriging variance costs at prediction (a script, not a test): ``python benchmarks/bench_kriging_predict.py``.

Issue #24: Kriging prediction used to compute the variance on every call. Through the library API
(:mod:`spflow.surrogates`) ``predict(X)`` now computes the mean only and ``predict(X, return_std=True)`` adds the
variance. This times both on the 8-input Borehole function (Surjanovic & Bingham's box) for a GP and a PC-Kriging
fitted on N Latin-hypercube runs, predicting 10^4 uniform points (and single points, the MCMC case); process CPU
seconds, the median of ``--repeat`` calls, BLAS on one thread as in the library. Run with ``nice -n 10``.
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np
from scipy.stats import qmc

from spflow.surrogates import GP, PCK

from analytic_functions import PROBLEMS, borehole

#: Borehole's input box, (lower, upper) per input rw, r, Tu, Hu, Tl, Hl, L, Kw.
BOREHOLE = np.column_stack(PROBLEMS["borehole"][1:])


def cpu(call, repeat: int) -> float:
    times = []
    for _ in range(repeat):
        start = time.process_time()
        call()
        times.append(time.process_time() - start)
    return statistics.median(times)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=200, help="training runs")
    parser.add_argument("--repeat", type=int, default=5)
    args = parser.parse_args()
    lower, upper = np.array(BOREHOLE, dtype=float).T
    x = qmc.scale(qmc.LatinHypercube(d=8, rng=0).random(args.n), lower, upper)
    xt = qmc.scale(np.random.default_rng(1).random((10_000, 8)), lower, upper)
    y = borehole(x)
    print(f"# Borehole, N = {args.n}, 10^4 prediction points; process CPU s, median of {args.repeat}")
    print("| model | fit (s) | predict(X) 10^4 (s) | predict(X, return_std=True) 10^4 (s) | ratio | 1 point mean (ms) "
          "| 1 point mean+std (ms) | eps_val |")
    print("|---|---|---|---|---|---|---|---|")
    for label, estimator in (("GP", GP(BOREHOLE)), ("PC-Kriging", PCK(BOREHOLE))):
        start = time.process_time()
        estimator.fit(x, y)
        fit = time.process_time() - start
        mean = cpu(lambda: estimator.predict(xt), args.repeat)
        both = cpu(lambda: estimator.predict(xt, return_std=True), args.repeat)
        one = cpu(lambda: [estimator.predict(xt[i:i + 1]) for i in range(100)], args.repeat) * 10
        one_std = cpu(lambda: [estimator.predict(xt[i:i + 1], return_std=True) for i in range(100)], args.repeat) * 10
        truth = borehole(xt)
        eps = float(np.mean((estimator.predict(xt) - truth) ** 2) / np.var(truth))
        print(f"| {label} | {fit:.2f} | {mean:.3f} | {both:.3f} | {both / mean:.1f} | {one:.3f} | {one_std:.3f} | "
              f"{eps:.2e} |")


if __name__ == "__main__":
    main()
