"""The LARS step of spflow's sparse PCE on its selected basis, a study script (not a test) for issue #24:
``python benchmarks/pce_ranking_study.py [--problems ishigami,g_function,borehole] [--sizes 50,100,200,400]``.

For each design (the Latin hypercubes and the 10^4 validation points of ``bench_surrogates_peers.py``) the default
``fit_pce(solver="lars")`` selects a basis A(p, q). On that fixed basis the script compares

* the two rankings of :mod:`spflow.plugins.surrogates.lars` (``ranking`` "lasso", the default, and "lar", plain
  least-angle regression), each with its prefix chosen by the corrected LOO and refitted by OLS: ε_val of each, and of
  the ranking a K-fold cross-validation of the LARS step picks (the smaller CV error);
* error estimates of the default (LASSO) model, over its ε_val: the corrected LOO it reports; the K-fold
  cross-validation of the LARS step on the fixed basis (ranking, prefix choice and OLS refit redone on K − 1 folds,
  folds of :func:`~spflow.plugins.surrogates.folds.fold_indices`); and that CV with Burman's
  correction for the smaller training sets ("corrected v-fold cross-validation", Burman 1989, Biometrika 76:503),
  CV + ε_emp(all N) − (1/K) Σ_k ε_N(fit_k), where ε_N(fit_k) is fold k's model's error on all N points.

Medians over seeds. Each K-fold CV costs K LARS fits on the fixed basis (per ranking): on the 8-input problems at
N = 400 (4000+ candidate terms) minutes of CPU; run with ``nice``.
"""

from __future__ import annotations

import argparse
import statistics
import warnings

import numpy as np
from scipy.stats import qmc

from spflow.plugins.surrogates.basis import design_matrix, multi_indices
from spflow.plugins.surrogates.degree_adaptive import fit_pce
from spflow.plugins.surrogates.lars import RANKINGS, hybrid_lars
from spflow.plugins.surrogates.folds import fold_indices

from analytic_functions import PROBLEMS
from bench_surrogates_peers import N_VALIDATION, VALIDATION_SEED


def lars_cv(psi: np.ndarray, y: np.ndarray, ranking: str, folds: int) -> tuple[float, float]:
    """(K-fold CV error of the LARS step on the fixed regressors ``psi``, mean over folds of the fold model's error
    on all N points), both relative to the population variance of ``y``."""
    residuals, everywhere = np.empty_like(y), []
    for held in fold_indices(y.size, folds):
        train = np.setdiff1d(np.arange(y.size), held)
        coefficients = hybrid_lars(psi[train], y[train], ranking).coefficients
        residuals[held] = psi[held] @ coefficients - y[held]
        everywhere.append(np.mean((psi @ coefficients - y) ** 2) / y.var())
    return float(np.mean(residuals**2) / y.var()), float(np.mean(everywhere))


def design(problem: str, n: int, seed: int, folds: list[int]) -> dict:
    """The quantities of one design (module docstring)."""
    func, lower, upper = PROBLEMS[problem]
    d = lower.size
    xv = lower + (upper - lower) * np.random.default_rng(VALIDATION_SEED).random((N_VALIDATION[problem], d))
    x = lower + (upper - lower) * qmc.LatinHypercube(d=d, seed=seed).random(n)
    y, yv = func(x), func(xv)
    z, zv = (2.0 * (a - lower) / (upper - lower) - 1.0 for a in (x, xv))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # degree-cap warnings
        fit = fit_pce(z, y, solver="lars")
    basis = multi_indices(d, fit.degree, fit.q)
    psi, psi_v = design_matrix(z, basis), design_matrix(zv, basis)
    row = {}
    for ranking in RANKINGS:
        model = hybrid_lars(psi, y, ranking)
        row[f"eps_{ranking}"] = float(np.mean((psi_v @ model.coefficients - yv) ** 2) / yv.var())
        row[f"loo_{ranking}"], row[f"emp_{ranking}"] = model.modified_loo, model.empirical
        for k in folds:
            row[f"cv{k}_{ranking}"], row[f"all{k}_{ranking}"] = lars_cv(psi, y, ranking, k)
    return row


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--problems", default=",".join(PROBLEMS))
    parser.add_argument("--sizes", default="50,100,200,400")
    parser.add_argument("--seeds", type=int, default=5)
    parser.add_argument("--folds", default="10",
                        help="comma-separated K of the fixed-basis cross-validations (docs/surrogates.md: 10,20 at "
                             "N <= 200, 10 at N = 400)")
    args = parser.parse_args()
    folds = [int(k) for k in args.folds.split(",")]
    head = ["eps lasso", "eps lar", f"eps CV{folds[0]}-chosen", "LOO/eps"] + \
        [f"CV{k}/eps" for k in folds] + [f"Burman CV{k}/eps" for k in folds]
    print("| problem | N | " + " | ".join(head) + " |")
    print("|---" * (len(head) + 2) + "|")
    for problem in args.problems.split(","):
        for n in (int(s) for s in args.sizes.split(",")):
            rows = [design(problem, n, seed, folds) for seed in range(args.seeds)]
            k = folds[0]
            chosen = [r[f"eps_{min(RANKINGS, key=lambda m: r[f'cv{k}_{m}'])}"] for r in rows]
            cells = [statistics.median(r["eps_lasso"] for r in rows), statistics.median(r["eps_lar"] for r in rows),
                     statistics.median(chosen), statistics.median(r["loo_lasso"] / r["eps_lasso"] for r in rows)]
            cells += [statistics.median(r[f"cv{k}_lasso"] / r["eps_lasso"] for r in rows) for k in folds]
            cells += [statistics.median((r[f"cv{k}_lasso"] + r["emp_lasso"] - r[f"all{k}_lasso"]) / r["eps_lasso"]
                                        for r in rows) for k in folds]
            print(f"| {problem} | {n} | " + " | ".join(f"{c:.2e}" if j < 3 else f"{c:.2f}"
                                                        for j, c in enumerate(cells)) + " |", flush=True)


if __name__ == "__main__":
    main()
