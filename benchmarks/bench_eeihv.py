"""EEIHV benchmark (a script, not a test): ``python benchmarks/bench_eeihv.py [--seeds 10] [--d 2] [--jobs 2]``.

Question (issue 8 acceptance): on a noisy two-objective problem with a known expected front, how many evaluations
does Bayesian global optimisation with EEIHV need to reach 95 % of the expected front's hypervolume, against random
search with the same kind of evaluations? Target: at most half.

Problem: ZDT1 (Zitzler, Deb & Thiele 2000) in d = 2 or 3 design variables on [0, 1]^d, f1 = x1,
f2 = g·(1 − √(f1/g)), g = 1 + 9·mean(x2..xd), observed with additive Gaussian noise of standard deviation
``--sigma`` on both objectives (one realisation per call, as in the method). The noise has zero mean, so the expected
front is the noise-free front f2 = 1 − √f1 (x2..xd = 0), whose hypervolume up to r = (1.1, 1.1) is
1.1² − 1/3 = 0.87667.

Score of a method after n evaluations: hypervolume of the *noise-free* objective values of all n evaluated designs
(the same rule for both methods). "n95" ("n80") is the first n at which it reaches 95 % (80 %) of 0.87667. EEIHV
starts from ``--n-init`` LHS designs and adds one design per iteration up to ``--budget`` evaluations (``min_iter``
= budget: the stopping rule is not used; printed are rel at the end and where the default rule, rel < 1e-2 after 10
iterations, would have stopped). Random search draws uniform designs up to ``--random-budget`` (default 10^6; n95 is
found by bisection, the fraction never decreases with n). A run that never reaches 95 % is censored (">budget");
means then use the budget (a lower bound). Also printed: the hypervolume fraction of the designs on EEIHV's
*projected* front at the end (what a user would pick without knowing the truth) and the wall time per EEIHV
iteration (GP fits dominate).

``--reference given`` passes the metric's reference point r to run_bgo; ``--reference data`` uses run_bgo's
default, pydes' data-driven rule (10 % beyond the projected range), which does not know r.
"""

from __future__ import annotations

import argparse
import time

import moocore
import numpy as np
from joblib import Parallel, delayed

from spflow.plugins.slug_design.bgo_loop import run_bgo

REFERENCE = np.array([1.1, 1.1])
EXPECTED_HV = 1.1 * 1.1 - 1.0 / 3.0


def zdt1(x: np.ndarray) -> np.ndarray:
    g = 1.0 + 9.0 * x[:, 1:].mean(axis=1)
    return np.column_stack([x[:, 0], g * (1.0 - np.sqrt(x[:, 0] / g))])


def hv_fraction(x: np.ndarray) -> float:
    """Hypervolume fraction of the expected front reached by the noise-free values at designs ``x``."""
    return moocore.hypervolume(zdt1(x), ref=REFERENCE) / EXPECTED_HV


def first_reaching(x: np.ndarray, level: float) -> int | None:
    """Smallest n whose first n designs reach ``level`` (bisection: the fraction never decreases with n)."""
    if hv_fraction(x) < level:
        return None
    low, high = 0, len(x)  # fraction(low) < level <= fraction(high)
    while high - low > 1:
        mid = (low + high) // 2
        low, high = (low, mid) if hv_fraction(x[:mid]) >= level else (mid, high)
    return high


def one_seed(seed: int, args) -> dict:
    rng = np.random.default_rng(10_000 + seed)

    def objective(x):
        return zdt1(x) + args.sigma * rng.standard_normal((x.shape[0], 2))

    start = time.perf_counter()
    iterations = args.budget - args.n_init
    result = run_bgo(objective, np.array([[0.0, 1.0]] * args.d), n_init=args.n_init, max_iter=iterations,
                     min_iter=iterations, seed=seed, gp_restarts=args.gp_restarts, n_candidates=args.candidates,
                     n_polish=args.polish, reference=REFERENCE if args.reference == "given" else None)
    seconds = time.perf_counter() - start
    random_x = np.random.default_rng(20_000 + seed).random((args.random_budget, args.d))
    # where run_bgo's stopping rule (rel < 1e-2 after min_iter = 10 iterations) would have stopped this run
    rel = result.eeihv_max / result.eeihv_max[0]
    stop = np.flatnonzero((rel < 1e-2) & (np.arange(rel.size) >= 10))
    stop_n = args.n_init + int(stop[0]) if stop.size else None
    return {"stop_n": stop_n, "stop_hv": hv_fraction(result.X[:stop_n]) if stop_n else None,
            "seed": seed, "n95": first_reaching(result.X, 0.95), "n80": first_reaching(result.X, 0.80),
            "final": hv_fraction(result.X), "projected": hv_fraction(result.X[result.front_index]),
            "rel": result.eeihv_max[-1] / result.eeihv_max[0], "seconds_per_iter": seconds / iterations,
            "random_n95": first_reaching(random_x, 0.95), "random_n80": first_reaching(random_x, 0.80),
            "random_at_budget": hv_fraction(random_x[:args.budget])}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=10)
    parser.add_argument("--d", type=int, default=2, choices=[2, 3])
    parser.add_argument("--sigma", type=float, default=0.05)
    parser.add_argument("--n-init", type=int, default=10)
    parser.add_argument("--budget", type=int, default=40)
    parser.add_argument("--random-budget", type=int, default=1_000_000)
    parser.add_argument("--gp-restarts", type=int, default=1)
    parser.add_argument("--candidates", type=int, default=1000)
    parser.add_argument("--polish", type=int, default=3)
    parser.add_argument("--reference", choices=["given", "data"], default="given")
    parser.add_argument("--jobs", type=int, default=2)
    args = parser.parse_args()

    start = time.perf_counter()
    rows = Parallel(n_jobs=args.jobs)(delayed(one_seed)(seed, args) for seed in range(args.seeds))
    wall = time.perf_counter() - start

    def show(n, budget):
        return f">{budget}" if n is None else str(n)

    print(f"noisy ZDT1, d = {args.d}, sigma = {args.sigma}, n_init = {args.n_init}, EEIHV budget = {args.budget}, "
          f"random budget = {args.random_budget}, reference {args.reference}, {args.seeds} seeds, "
          f"wall {wall:.0f} s with {args.jobs} workers")
    print("seed | EEIHV n95 | EEIHV n80 | EEIHV HV@budget | projected-front HV | rel at end | rtol stop: n, HV | "
          "s/iter | random n95 | random n80 | random HV@budget")
    for r in rows:
        print(f"{r['seed']:4d} | {show(r['n95'], args.budget):>9} | {show(r['n80'], args.budget):>9} | "
              f"{r['final']:15.3f} | {r['projected']:18.3f} | {r['rel']:10.3f} | "
              f"{show(r['stop_n'], args.budget):>4}, {r['stop_hv'] or float('nan'):5.3f}    | "
              f"{r['seconds_per_iter']:6.2f} | "
              f"{show(r['random_n95'], args.random_budget):>10} | {show(r['random_n80'], args.random_budget):>10} | "
              f"{r['random_at_budget']:16.3f}")
    for level in ("n95", "n80"):
        eeihv_n = np.array([r[level] or args.budget for r in rows], dtype=float)
        random_n = np.array([r["random_" + level] or args.random_budget for r in rows], dtype=float)
        censored = sum(r[level] is None for r in rows), sum(r["random_" + level] is None for r in rows)
        ratio = eeihv_n.mean() / random_n.mean()
        verdict = ("indeterminate (EEIHV censored)" if censored[0] else
                   f"< {ratio:.3f} (random censored: a bound)" if censored[1] else f"{ratio:.3f}")
        print(f"mean {level}: EEIHV {eeihv_n.mean():.1f} ({censored[0]} censored at {args.budget}), random "
              f"{random_n.mean():.1f} ({censored[1]} censored at {args.random_budget}); ratio EEIHV/random {verdict}; "
              f"medians {np.median(eeihv_n):.0f} / {np.median(random_n):.0f}")

if __name__ == "__main__":
    main()
