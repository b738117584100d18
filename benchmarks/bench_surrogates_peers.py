"""Sparse PCE against its peers (a script, not a test): ``python benchmarks/bench_surrogates_peers.py [--quick]``.

Issue #24, first part: spflow's default sparse PCE (hybrid LARS, degree- and q-adaptive, :class:`PCE.fit`) against

* OpenTURNS (``pip install openturns``, or the ``bench`` extra of pyproject.toml): ``FunctionalChaosAlgorithm`` with
  ``LeastSquaresMetaModelSelectionFactory(LARS(), CorrectedLeaveOneOut())`` on a fixed candidate basis (OpenTURNS does
  not search the degree itself): the largest of spflow's candidate sets A(p, q) — spflow's default q, p <= spflow's
  default ``degree_max`` — within spflow's basis-size limit, given to OpenTURNS as the first |A(p, q)| functions of
  its ``HyperbolicAnisotropicEnumerateFunction(d, q)`` (the same set: that enumeration orders by q-norm);
* chaospy ordinary least squares (``fit_regression``) at a degree fixed before seeing the data: the largest total
  degree whose full basis has at most N/2 terms (two runs per coefficient).

Problems (uniform inputs only): Ishigami (a = 7, b = 0.1, X ~ U(-π, π)^3); the Sobol G-function with d = 8 and
a = (0, 1, 4.5, 9, 99, 99, 99, 99) on [0, 1]^8; Borehole on the uniform box of Surjanovic & Bingham's library
(8 inputs). For each N in {50, 100, 200, 400} and 5 seeds, every method gets the same Latin hypercube
(``scipy.stats.qmc.LatinHypercube(d, seed=seed)``) and is validated on the same 10^4 independent uniform points.

Columns (medians over the seeds):

* ``eps_val``: validation error, mean squared error / variance of the validation outputs (the form of Eq. 3.8);
* ``LOO/eps``: the method's own leave-one-out estimate divided by ``eps_val``. spflow: the error the model reports for
  a calibration (``PCE.error_variance / output_variance``); OpenTURNS: the corrected LOO of the selected basis (the
  smallest entry of ``getErrorHistory``); chaospy: the plain LOO of the OLS fit from its hat matrix (chaospy has no
  error estimate; computed here);
* ``fit CPU``: process CPU time of the fit, seconds (OpenTURNS' own threads included);
* ``p``: the median selected (spflow) or fixed (peers) total degree.

Not covered yet (left for later parts of #24): spflow's simulator as a test problem, non-uniform inputs, Kriging
peers and a library-style ``fit(X, y)`` API. Run with ``nice -n 10``; the full table takes a few minutes of CPU.
``--methods spflow`` times spflow alone (e.g. with another checkout first on PYTHONPATH, for a before/after table).
"""

from __future__ import annotations

import argparse
import datetime
import inspect
import math
import os
import statistics
import time
import warnings

import numpy as np
from scipy.stats import qmc

from spflow.plugins.surrogates.basis import multi_indices
from spflow.plugins.surrogates.degree_adaptive import fit_pce
from spflow.plugins.surrogates.outputs import OutputIndex
from spflow.plugins.surrogates.pce_model import PCE

N_VALIDATION = 10_000
VALIDATION_SEED = 20_241_124


def ishigami(x: np.ndarray) -> np.ndarray:
    return np.sin(x[:, 0]) + 7.0 * np.sin(x[:, 1]) ** 2 + 0.1 * x[:, 2] ** 4 * np.sin(x[:, 0])


G_A = np.array([0.0, 1.0, 4.5, 9.0, 99.0, 99.0, 99.0, 99.0])


def g_function(x: np.ndarray) -> np.ndarray:
    return np.prod((np.abs(4.0 * x - 2.0) + G_A) / (1.0 + G_A), axis=1)


def borehole(x: np.ndarray) -> np.ndarray:
    rw, r, tu, hu, tl, hl, length, kw = x.T
    log_ratio = np.log(r / rw)
    return 2.0 * np.pi * tu * (hu - hl) / (log_ratio * (1.0 + 2.0 * length * tu / (log_ratio * rw**2 * kw) + tu / tl))


PROBLEMS = {
    "ishigami": (ishigami, np.full(3, -np.pi), np.full(3, np.pi)),
    "g_function": (g_function, np.zeros(8), np.ones(8)),
    "borehole": (borehole, np.array([0.05, 100.0, 63070.0, 990.0, 63.1, 700.0, 1120.0, 9855.0]),
                 np.array([0.15, 50000.0, 115600.0, 1110.0, 116.0, 820.0, 1680.0, 12045.0])),
}


def spflow_defaults() -> dict:
    """fit_pce's defaults (degree cap, q, basis-size ratio)."""
    params = inspect.signature(fit_pce).parameters
    return {name: p.default for name, p in params.items() if p.default is not inspect.Parameter.empty}


def relative_error(prediction: np.ndarray, truth: np.ndarray) -> float:
    return float(np.mean((prediction - truth) ** 2) / np.var(truth))


def fit_spflow(x, y, lower, upper, xv):
    outputs = OutputIndex(np.array(["y"]), np.array([""]), np.array([np.nan]), {"y": "1"})
    names = [f"x{k}" for k in range(x.shape[1])]
    start = time.process_time()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the degree-cap warning is counted from the model's attrs instead
        model = PCE.fit(names, lower, upper, outputs, x, y[:, None], solver="lars")
    cpu = time.process_time() - start
    reported = float(model.error_variance[0] / model.output_variance[0])
    return model.predict(xv)[0][:, 0], reported, cpu, model.info["degree"]


def ot_basis(d: int, n: int) -> tuple[int, int]:
    """(degree, number of terms) of the candidate set given to OpenTURNS: the largest A(p, q) spflow may try."""
    # imported here, not at the top: ``--methods spflow`` must also run on an spflow without it (before/after tables)
    from spflow.plugins.surrogates.degree_adaptive import MIN_TERMS

    defaults = spflow_defaults()
    limit = max(defaults["max_terms_ratio"] * n, MIN_TERMS)
    degree = 1
    while degree < defaults["degree_max"] and multi_indices(d, degree + 1, defaults["q"]).shape[0] <= limit:
        degree += 1
    return degree, multi_indices(d, degree, defaults["q"]).shape[0]


def fit_openturns(x, y, lower, upper, xv):
    import openturns as ot

    ot.Log.Show(ot.Log.NONE)
    d = x.shape[1]
    degree, size = ot_basis(d, x.shape[0])
    start = time.process_time()
    distribution = ot.JointDistribution([ot.Uniform(float(a), float(b)) for a, b in zip(lower, upper)])
    enum = ot.HyperbolicAnisotropicEnumerateFunction(d, float(spflow_defaults()["q"]))
    basis = ot.OrthogonalProductPolynomialFactory([ot.LegendreFactory()] * d, enum)
    selection = ot.LeastSquaresMetaModelSelectionFactory(ot.LARS(), ot.CorrectedLeaveOneOut())
    algo = ot.FunctionalChaosAlgorithm(ot.Sample(x), ot.Sample(y[:, None]), distribution,
                                       ot.FixedStrategy(basis, size),
                                       ot.LeastSquaresStrategy(selection))
    algo.run()
    result = algo.getResult()
    cpu = time.process_time() - start
    loo = float(np.min(np.asarray(result.getErrorHistory())))
    return np.asarray(result.getMetaModel()(ot.Sample(xv)))[:, 0], loo, cpu, degree


def fit_chaospy(x, y, lower, upper, xv):
    import chaospy

    d, n = x.shape[1], x.shape[0]
    degree = 1
    while math.comb(degree + 1 + d, d) <= n / 2:  # full total-degree basis of degree + 1
        degree += 1
    start = time.process_time()
    distribution = chaospy.J(*[chaospy.Uniform(float(a), float(b)) for a, b in zip(lower, upper)])
    expansion = chaospy.generate_expansion(degree, distribution, normed=True)
    model = chaospy.fit_regression(expansion, x.T, y)
    cpu = time.process_time() - start
    psi = np.asarray(expansion(*x.T)).T
    q, _ = np.linalg.qr(psi)
    leverage = np.sum(q**2, axis=1)
    residual = y - np.asarray(model(*x.T))
    loo = float(np.mean((residual / (1.0 - leverage)) ** 2) / np.var(y))
    return np.asarray(model(*xv.T)), loo, cpu, degree


METHODS = {"spflow": fit_spflow, "openturns": fit_openturns, "chaospy": fit_chaospy}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="2 seeds, N in {50, 200}")
    parser.add_argument("--methods", default=",".join(METHODS), help="comma-separated subset of " + ", ".join(METHODS))
    parser.add_argument("--problems", default=",".join(PROBLEMS), help="comma-separated subset of problems")
    args = parser.parse_args()
    methods = args.methods.split(",")
    sizes, seeds = ((50, 200), range(2)) if args.quick else ((50, 100, 200, 400), range(5))
    print(f"# {datetime.date.today()}; spflow fit_pce defaults {spflow_defaults()}; "
          f"load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} CPUs; medians over {len(seeds)} seeds")
    print("| problem | N | method | p | eps_val | LOO/eps | fit CPU (s) |")
    print("|---|---|---|---|---|---|---|")
    total = time.process_time()
    for problem in args.problems.split(","):
        func, lower, upper = PROBLEMS[problem]
        d = lower.size
        xv = lower + (upper - lower) * np.random.default_rng(VALIDATION_SEED).random((N_VALIDATION, d))
        yv = func(xv)
        for n in sizes:
            for method in methods:
                rows = []
                for seed in seeds:
                    x = lower + (upper - lower) * qmc.LatinHypercube(d=d, seed=seed).random(n)
                    prediction, loo, cpu, degree = METHODS[method](x, func(x), lower, upper, xv)
                    eps = relative_error(prediction, yv)
                    rows.append((eps, loo / eps, cpu, degree))
                eps, ratio, cpu, degree = (statistics.median(c) for c in zip(*rows))
                print(f"| {problem} | {n} | {method} | {degree:g} | {eps:.2e} | {ratio:.2f} | {cpu:.3f} |", flush=True)
    print(f"# total CPU {time.process_time() - total:.0f} s")


if __name__ == "__main__":
    main()
