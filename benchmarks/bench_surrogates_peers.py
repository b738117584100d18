"""Surrogates against their peers (a script, not a test): ``python benchmarks/bench_surrogates_peers.py [--quick]``.

Issue #24. Sparse PCE (the default ``--methods``): spflow's default sparse PCE (hybrid LARS, degree- and q-adaptive,
:class:`PCE.fit`) against

* OpenTURNS (``pip install openturns``, or the ``bench`` extra of pyproject.toml): ``FunctionalChaosAlgorithm`` with
  ``LeastSquaresMetaModelSelectionFactory(LARS(), CorrectedLeaveOneOut())`` on a fixed candidate basis (OpenTURNS does
  not search the degree itself): the largest of spflow's candidate sets A(p, q) — spflow's default q, p <= spflow's
  default ``degree_max`` — within spflow's basis-size limit, given to OpenTURNS as the first |A(p, q)| functions of
  its ``HyperbolicAnisotropicEnumerateFunction(d, q)`` (the same set: that enumeration orders by q-norm); one fit per
  output column;
* chaospy ordinary least squares (``fit_regression``) at a degree fixed before seeing the data: the largest total
  degree whose full basis has at most N/2 terms (two runs per coefficient).

Kriging (``--methods spflow_gp,spflow_gp_matern,spflow_pck,spflow_pck_mean,sklearn_gp_rbf,sklearn_gp_matern``):
spflow's ``GP`` (Gaussian or Matérn 5/2 kernel) and ``PCK`` from :mod:`spflow.surrogates` with their defaults
(``spflow_pck_mean`` is the same PC-Kriging fit scored by the Sobol indices of its whole predictor instead of its
trend's), against scikit-learn's ``GaussianProcessRegressor`` (see :func:`fit_sklearn_gp`). One model per output
column throughout.

Problems, inputs uniform: Ishigami (a = 7, b = 0.1, X ~ U(-π, π)^3); the Sobol G-function with d = 8 and
a = (0, 1, 4.5, 9, 99, 99, 99, 99) on [0, 1]^8; Borehole on the uniform box of Surjanovic & Bingham's library
(8 inputs); ``simulator``: spflow's forward model, BCF1 on 30 cells over the 9 parameters of thesis Table 3.2, with
20 outputs (Δp and oil cut at 10 PV points; ``peer_simulator.py``, runs cached under ``--cache``). For each N in
{50, 100, 200, 400} and 5 seeds (``--seeds``; ``--simulator-seeds`` caps them on the simulator, whose table costs
~8 min of CPU with 5, mostly OpenTURNS' 20 fits per design at N = 400), every method gets the same Latin hypercube
(``scipy.stats.qmc.LatinHypercube(d, seed=seed)``) and is validated on the same independent uniform points (10^4;
10^3 simulator runs).

Columns (medians over the output columns of a fit, then over the seeds):

* ``eps_val``: validation error, mean squared error / variance of the validation outputs (the form of Eq. 3.8);
  columns whose validation outputs are constant up to round-off are not scored;
* ``LOO/eps``: the method's own leave-one-out estimate divided by ``eps_val``. spflow PCE: the error the model
  reports for a calibration (``PCE.error_variance / output_variance``: the corrected LOO; ``spflow_cv``, the same fit
  with ``cv_folds=10``: the 10-fold cross-validation error of the whole adaptive fit; ``spflow_min_loo``, the same fit
  with ``prefix_rule="min_loo"`` (the default before the one-SE rule), and ``spflow_one_se_cv``, with
  ``ranking="cv", prefix_rule="one_se"``: the corrected LOO of the model they keep); spflow GP/PCK: their Kriging (Dubrule) LOO; OpenTURNS: the corrected LOO of the
  selected basis (the smallest entry of ``getErrorHistory``); chaospy: the plain LOO of the OLS fit from its hat matrix
  (chaospy has no error estimate; computed here); scikit-learn: the closed-form LOO of the fitted GP (computed here);
* ``fit CPU``: process CPU time of the fit of all columns, seconds (the peers' own threads included);
* ``predict CPU``: process CPU time of the prediction of all columns at the validation points (10^4; simulator 10^3),
  mean only where the API allows it (spflow ``predict_mean``/``predict(X)``, scikit-learn ``predict(X)``; a PCE has
  no pointwise variance to skip), seconds, the smallest of ``PREDICT_REPEATS`` = 3 calls;
* ``S1 max err``, ``ST max err``: max over the inputs of |S_i - S_i,ref| (first order) and of |S_Ti - S_Ti,ref|
  (total). The method's own indices: spflow's PCE its coefficients' (``PCE.sobol()``), OpenTURNS
  ``FunctionalChaosSobolIndices`` of its result, chaospy the coefficient formula on its orthonormal basis,
  ``spflow_pck`` its trend's (``PCK.sobol_indices(part="trend")``). The Kriging predictors (spflow GP,
  ``spflow_pck_mean``, scikit-learn) have none in closed form: a pick-freeze estimate on the predictor mean by this
  benchmark's own estimator, not the library's ``GP``/``PCK`` ``sobol_indices()`` (``saltelli_design.py``: Saltelli
  et al. 2010's first-order and Jansen's total estimator) on one fixed scrambled Sobol' design of ``MC_BASE`` base
  points, the same for every Kriging method; the script prints that estimator's own
  error on the true function (6e-6 to 4e-4 on the analytic problems). References, independent of the methods:
  Ishigami and the G-function in closed form (``analytic_functions.CLOSED_FORM_SOBOL``: Ishigami & Homma 1990,
  Sobol' 1990, Saltelli et al. 2010; tested against Monte Carlo); Borehole and the simulator the mean of independent
  scrambled-Sobol' pick-freeze estimates on the true function (``REFERENCE_DESIGN``: Borehole 8 x 2^16 base points,
  standard error ~2e-5; the simulator 4 x 256, i.e. 11 264 runs, ~80 s of CPU once, cached, standard error ~7e-3,
  which is the size of most methods' simulator errors from N = 200 on), with their standard error printed;
* ``p``: the median selected (spflow) or fixed (peers) total degree of a PCE ("-" for Kriging).

Not covered (later parts of #24): non-uniform inputs, SMT's Kriging; the pick-freeze estimator's own error on the
simulator (it would take (d + 2) 2^13 runs). Run with ``nice -n 10``; the analytic PCE table takes a few minutes of
CPU, the simulator's ~8 min (runs ~35 s of it) plus the one-off reference runs.
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
from pathlib import Path
from typing import NamedTuple

import numpy as np
from scipy.stats import qmc

from spflow.plugins.surrogates.basis import multi_indices
from spflow.plugins.surrogates.degree_adaptive import fit_pce
from spflow.plugins.surrogates.outputs import OutputIndex
from spflow.plugins.surrogates.pce_model import PCE
from spflow.plugins.surrogates.regression import is_constant
from spflow.plugins.surrogates.sobol_from_pce import first_order, total_order
from spflow.surrogates import GP, PCK

from peer_simulator import LOWER, UPPER, simulator_outputs
from analytic_functions import CLOSED_FORM_SOBOL, PROBLEMS
from saltelli_design import PickFreeze, replicated_indices

N_VALIDATION = {"ishigami": 10_000, "g_function": 10_000, "borehole": 10_000, "simulator": 1_000}
VALIDATION_SEED = 20_241_124
#: base points of the pick-freeze design on which the Kriging predictors' Sobol indices are estimated, and its seed
MC_BASE = {"ishigami": 2**14, "g_function": 2**14, "borehole": 2**14, "simulator": 2**13}
MC_SEED = 7
#: (base points, independent scramblings) of the reference indices of the problems without a closed form
REFERENCE_DESIGN = {"borehole": (2**16, 8), "simulator": (256, 4)}
REFERENCE_SEED = 1000
PREDICT_REPEATS = 3  # prediction CPU: the smallest of this many calls
CHUNK = 20_000  # points per predictor call on the pick-freeze design (bounds the Kriging cross-covariance's memory)


class Result(NamedTuple):
    """What a method returns for one design: its predictions at the validation points (n_val, m), its own error
    estimate per column (m,), fit CPU (s), the PCE degree (NaN for Kriging), prediction CPU (s) at the validation
    points, and its first-order and total Sobol indices, each (m, d)."""

    prediction: np.ndarray
    loo: np.ndarray
    fit_cpu: float
    degree: float
    predict_cpu: float
    first: np.ndarray
    total: np.ndarray


def timed(predict, points: np.ndarray, repeats: int = PREDICT_REPEATS) -> tuple[np.ndarray, float]:
    """(predict(points), its process CPU time in s: the smallest of ``repeats`` calls, as ``timeit`` does; on a shared
    machine single calls of a few ms scatter several-fold)."""
    cpu = math.inf
    for _ in range(repeats):
        start = time.process_time()
        values = predict(points)
        cpu = min(cpu, time.process_time() - start)
    return values, cpu


def in_chunks(predict, points: np.ndarray) -> np.ndarray:
    """predict(points) evaluated CHUNK rows at a time, stacked (n, m)."""
    return np.concatenate([np.asarray(predict(points[k:k + CHUNK])).reshape(min(CHUNK, points.shape[0] - k), -1)
                           for k in range(0, points.shape[0], CHUNK)])


def spflow_defaults() -> dict:
    """fit_pce's defaults (degree cap, q, basis-size ratio)."""
    params = inspect.signature(fit_pce).parameters
    return {name: p.default for name, p in params.items() if p.default is not inspect.Parameter.empty}


def relative_errors(prediction: np.ndarray, truth: np.ndarray) -> np.ndarray:
    """Per column: validation mean squared error / variance of the validation outputs (the form of Eq. 3.8); NaN for
    a column whose validation outputs are constant up to round-off (nothing to score)."""
    spread = np.var(truth, axis=0)
    error = np.mean((prediction - truth) ** 2, axis=0)
    return np.where(is_constant(truth), np.nan, error / np.where(spread > 0, spread, 1.0))


def fit_spflow(**options):
    """spflow's default sparse PCE with ``options`` over its defaults, all columns of ``y`` (n, m) in one fit (they
    share the degree and q); its error estimate is the one it reports (the corrected LOO, or the K-fold
    cross-validation error of the whole fit with ``cv_folds``); its Sobol indices those of its coefficients
    (``PCE.sobol()``); prediction by ``predict_mean``."""
    def fit(x, y, lower, upper, xv, design):
        outputs = OutputIndex.of_array(y.shape[1])
        names = [f"x{k}" for k in range(x.shape[1])]
        start = time.process_time()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # the degree-cap warning is counted from the model's attrs instead
            model = PCE.fit(names, lower, upper, outputs, x, y, solver="lars", **options)
        cpu = time.process_time() - start
        with np.errstate(divide="ignore", invalid="ignore"):
            reported = model.error_variance / model.output_variance
        prediction, predict_cpu = timed(model.predict_mean, xv)
        sobol = model.sobol()
        return Result(prediction, reported, cpu, model.info["degree"], predict_cpu, sobol["S1"].values,
                      sobol["ST"].values)
    return fit


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


def fit_openturns(x, y, lower, upper, xv, design):
    """OpenTURNS' LARS PCE with corrected LOO on spflow's largest candidate set, one fit per column of ``y``; Sobol
    indices from ``FunctionalChaosSobolIndices`` of each result; prediction: each column's metamodel on an
    ``ot.Sample`` of the points (the conversion timed with it)."""
    import openturns as ot

    ot.Log.Show(ot.Log.NONE)
    d = x.shape[1]
    degree, size = ot_basis(d, x.shape[0])
    results, loo = [], []
    start = time.process_time()
    distribution = ot.JointDistribution([ot.Uniform(float(a), float(b)) for a, b in zip(lower, upper)])
    enum = ot.HyperbolicAnisotropicEnumerateFunction(d, float(spflow_defaults()["q"]))
    basis = ot.OrthogonalProductPolynomialFactory([ot.LegendreFactory()] * d, enum)
    for column in y.T:
        selection = ot.LeastSquaresMetaModelSelectionFactory(ot.LARS(), ot.CorrectedLeaveOneOut())
        algo = ot.FunctionalChaosAlgorithm(ot.Sample(x), ot.Sample(column[:, None]), distribution,
                                           ot.FixedStrategy(basis, size), ot.LeastSquaresStrategy(selection))
        algo.run()
        result = algo.getResult()
        loo.append(float(np.min(np.asarray(result.getErrorHistory()))))
        results.append(result)
    cpu = time.process_time() - start
    models = [r.getMetaModel() for r in results]
    prediction, predict_cpu = timed(lambda p: np.column_stack([np.asarray(m(ot.Sample(p)))[:, 0] for m in models]),
                                    xv)
    indices = [ot.FunctionalChaosSobolIndices(r) for r in results]
    first = np.array([[s.getSobolIndex(i) for i in range(d)] for s in indices])
    total = np.array([[s.getSobolTotalIndex(i) for i in range(d)] for s in indices])
    return Result(prediction, np.array(loo), cpu, degree, predict_cpu, first, total)


def fit_chaospy(x, y, lower, upper, xv, design):
    """chaospy OLS on the full total-degree basis, all columns of ``y`` (n, m) on the same basis. Its Sobol indices
    from its coefficients on the orthonormal basis (``normed=True``; the formulas of Sudret 2008, through
    :mod:`spflow.plugins.surrogates.sobol_from_pce`, with each basis polynomial's multi-index read off its
    exponents): chaospy's symbolic ``Sens_m``/``Sens_t`` take minutes at a few hundred terms."""
    import chaospy

    d, n = x.shape[1], x.shape[0]
    degree = 1
    while math.comb(degree + 1 + d, d) <= n / 2:  # full total-degree basis of degree + 1
        degree += 1
    start = time.process_time()
    distribution = chaospy.J(*[chaospy.Uniform(float(a), float(b)) for a, b in zip(lower, upper)])
    expansion = chaospy.generate_expansion(degree, distribution, normed=True)
    model, coefficients = chaospy.fit_regression(expansion, x.T, y, retall=1)
    cpu = time.process_time() - start
    psi = np.asarray(expansion(*x.T)).T
    q, _ = np.linalg.qr(psi)
    leverage = np.sum(q**2, axis=1)
    residual = y - np.asarray(model(*x.T)).T
    with np.errstate(divide="ignore", invalid="ignore"):
        loo = np.mean((residual / (1.0 - leverage[:, None])) ** 2, axis=0) / np.var(y, axis=0)
    prediction, predict_cpu = timed(lambda p: np.asarray(model(*p.T)).T.reshape(p.shape[0], -1), xv)
    indices = np.array([np.asarray(p.exponents).max(axis=0) for p in expansion])  # constant term first
    coefficients = np.asarray(coefficients).reshape(len(expansion), -1).T  # (m, P)
    return Result(prediction, loo, cpu, degree, predict_cpu, first_order(indices, coefficients),
                  total_order(indices, coefficients))


def fit_spflow_kriging(estimator, trend_sobol: bool = False, **options):
    """spflow's GP or PC-Kriging (``spflow.surrogates``) with ``options`` over its defaults, one model per column
    (``share="output"``, the default); its reported error is the Kriging (Dubrule) LOO; prediction ``predict(X)``
    (mean only). Sobol indices: the pick-freeze estimate on the predictor mean (``design``), or with ``trend_sobol``
    PC-Kriging's ``sobol_indices(part="trend")`` (its trend's, read off the coefficients)."""
    def fit(x, y, lower, upper, xv, design):
        start = time.process_time()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # PCK's degree-3 trend cap
            model = estimator(np.column_stack([lower, upper]), **options).fit(x, y)
        cpu = time.process_time() - start
        prediction, predict_cpu = timed(model.predict, xv)
        if trend_sobol:
            indices = model.sobol_indices(part="trend")
            first, total = indices.first, indices.total
        else:
            first, total = design.indices(in_chunks(model.predict, design.points))
        return Result(prediction, np.atleast_1d(model.loo_error_), cpu, math.nan, predict_cpu, first, total)
    return fit


def fit_sklearn_gp(kernel: str):
    """scikit-learn's ``GaussianProcessRegressor`` on the inputs mapped onto [-1, 1]^d (spflow's Kriging space).

    ``ConstantKernel() * RBF`` or ``* Matern(nu=2.5)`` with one length scale per input (``kernel`` "rbf" or
    "matern52") bounded as spflow's (``LENGTHSCALE_BOUNDS``), ``normalize_y=True``, 2 optimiser restarts (3 runs, as
    spflow's ``restarts=3``); everything else scikit-learn's default (alpha = 1e-10 on the diagonal). With
    scikit-learn's default length-scale bounds (1e-5, 1e5) the RBF fits on Ishigami end at ℓ = 1e-5 (white noise,
    ε_val = 1) from every start. One model per column, BLAS on one thread (spflow's fits run on one). Its reported
    error is the closed-form LOO of the fitted GP (Rasmussen & Williams 2006, Eq. 5.12), without refitting the
    hyperparameters. Prediction: ``predict(X)`` (mean only) per column; Sobol indices: the pick-freeze estimate on
    the predictor mean (``design``), as for spflow's GP."""
    def fit(x, y, lower, upper, xv, design):
        from sklearn.gaussian_process import GaussianProcessRegressor
        from sklearn.gaussian_process.kernels import RBF, ConstantKernel, Matern
        from threadpoolctl import threadpool_limits

        from spflow.plugins.surrogates.kriging_likelihood import LENGTHSCALE_BOUNDS

        d = x.shape[1]
        z, zv, zs = (2.0 * (a - lower) / (upper - lower) - 1.0 for a in (x, xv, design.points))
        bounds = LENGTHSCALE_BOUNDS
        shape = RBF(np.ones(d), bounds) if kernel == "rbf" else Matern(np.ones(d), bounds, nu=2.5)
        loo, models = [], []
        start = time.process_time()
        with threadpool_limits(limits=1, user_api="blas"), warnings.catch_warnings():
            warnings.simplefilter("ignore")  # ConvergenceWarning at a bound
            for column in y.T:
                gp = GaussianProcessRegressor(ConstantKernel() * shape, normalize_y=True, n_restarts_optimizer=2,
                                              random_state=0)
                models.append(gp.fit(z, column))
        cpu = time.process_time() - start
        for gp, column in zip(models, y.T):
            inverse = np.linalg.inv(gp.kernel_(z) + gp.alpha * np.eye(z.shape[0]))
            scaled = (column - column.mean()) / column.std()  # normalize_y's scaling
            residual = (inverse @ scaled) / np.diag(inverse) * column.std()
            loo.append(float(np.mean(residual**2) / np.var(column)))
        with threadpool_limits(limits=1, user_api="blas"):
            prediction, predict_cpu = timed(lambda p: np.column_stack([gp.predict(p) for gp in models]), zv)
            first, total = design.indices(in_chunks(lambda p: np.column_stack([gp.predict(p) for gp in models]), zs))
        return Result(prediction, np.array(loo), cpu, math.nan, predict_cpu, first, total)
    return fit


METHODS = {"spflow": fit_spflow(), "spflow_cv": fit_spflow(cv_folds=10),
           "spflow_min_loo": fit_spflow(prefix_rule="min_loo"),
           "spflow_one_se_cv": fit_spflow(ranking="cv", prefix_rule="one_se"), "openturns": fit_openturns,
           "chaospy": fit_chaospy,
           "spflow_gp": fit_spflow_kriging(GP), "spflow_gp_matern": fit_spflow_kriging(GP, kernel="matern52"),
           "spflow_pck": fit_spflow_kriging(PCK, trend_sobol=True), "spflow_pck_mean": fit_spflow_kriging(PCK),
           "sklearn_gp_rbf": fit_sklearn_gp("rbf"),
           "sklearn_gp_matern": fit_sklearn_gp("matern52")}
PCE_METHODS = "spflow,openturns,chaospy"


def problems(cache: Path) -> dict:
    """name -> (function of x (n, d) giving y (n, m), lower, upper)."""
    table = {name: (lambda x, f=func: f(x)[:, None], lower, upper) for name, (func, lower, upper) in PROBLEMS.items()}
    table["simulator"] = (lambda x: simulator_outputs(x, cache), LOWER, UPPER)
    return table


def reference_indices(problem: str, func, lower: np.ndarray, upper: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Reference (first-order, total) Sobol indices of ``problem``, each (m, d), computed independently of the
    methods: the closed forms of Ishigami and the G-function, else the mean of independent randomised-QMC pick-freeze
    estimates on the true function (``REFERENCE_DESIGN``), whose standard error is printed."""
    if problem in CLOSED_FORM_SOBOL:
        first, total = CLOSED_FORM_SOBOL[problem]()
        print(f"# {problem}: reference Sobol indices in closed form")
        return first[None], total[None]
    n_base, replicates = REFERENCE_DESIGN[problem]
    start = time.process_time()
    first, total, se_first, se_total = replicated_indices(func, lower, upper, n_base, replicates, REFERENCE_SEED)
    print(f"# {problem}: reference Sobol indices from {replicates} scrambled-Sobol' pick-freeze designs of {n_base} "
          f"base points ({replicates * n_base * (lower.size + 2)} runs of the true function, "
          f"{time.process_time() - start:.0f} s CPU); standard error of the reference, max over inputs, median "
          f"(max) over outputs: S1 {np.nanmedian(np.nanmax(se_first, axis=1)):.1e} "
          f"({np.nanmax(se_first):.1e}), ST {np.nanmedian(np.nanmax(se_total, axis=1)):.1e} "
          f"({np.nanmax(se_total):.1e})")
    return first, total


def sobol_errors(first: np.ndarray, total: np.ndarray, reference: tuple[np.ndarray, np.ndarray],
                 scored: np.ndarray) -> tuple[float, float]:
    """Median over the scored output columns of max_i |S_i - S_i,ref| and of max_i |S_Ti - S_Ti,ref|."""
    return tuple(float(np.median(np.max(np.abs(mine - ref), axis=1)[scored]))
                 for mine, ref in zip((first, total), reference))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="2 seeds, N in {50, 200}")
    parser.add_argument("--methods", default=PCE_METHODS, help="comma-separated subset of " + ", ".join(METHODS))
    parser.add_argument("--problems", default=",".join([*PROBLEMS, "simulator"]),
                        help="comma-separated subset of " + ", ".join([*PROBLEMS, "simulator"]))
    parser.add_argument("--sizes", default=None, help="comma-separated training sizes (default 50,100,200,400)")
    parser.add_argument("--seeds", type=int, default=None, help="seeds per N (default 5, --quick 2)")
    parser.add_argument("--first-seed", type=int, default=0, help="seeds first-seed, first-seed + 1, ... (fresh designs)")
    parser.add_argument("--simulator-seeds", type=int, default=5, help="at most this many seeds per N on the simulator")
    parser.add_argument("--cache", type=Path, default=Path("/tmp/spflow_bench_peers"),
                        help="directory of the simulator's cached runs (.npz, one per design)")
    args = parser.parse_args()
    methods = args.methods.split(",")
    sizes, seeds = ((50, 200), 2) if args.quick else ((50, 100, 200, 400), 5)
    sizes = tuple(int(n) for n in args.sizes.split(",")) if args.sizes else sizes
    seeds = args.seeds or seeds
    table = problems(args.cache)
    print(f"# {datetime.date.today()}; spflow fit_pce defaults {spflow_defaults()}; "
          f"load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} CPUs; medians over outputs, then over seeds")
    print("| problem | N | seeds | method | p | eps_val | LOO/eps | fit CPU (s) | predict CPU (s) | S1 max err "
          "| ST max err |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    total = time.process_time()
    for problem in args.problems.split(","):
        func, lower, upper = table[problem]
        d = lower.size
        xv = lower + (upper - lower) * np.random.default_rng(VALIDATION_SEED).random((N_VALIDATION[problem], d))
        yv = func(xv)
        reference = reference_indices(problem, func, lower, upper)
        design = PickFreeze(lower, upper, MC_BASE[problem], MC_SEED)
        if problem != "simulator":  # the estimator's own error, on the true function (the simulator: too many runs)
            floor = sobol_errors(*design.indices(func(design.points)), reference, np.ones(1, dtype=bool))
            print(f"# {problem}: Kriging indices estimated on {MC_BASE[problem]} base points ({design.points.shape[0]}"
                  f" predictions); the same estimator on the true function is off by S1 {floor[0]:.1e}, "
                  f"ST {floor[1]:.1e}")
        n_seeds = min(args.simulator_seeds, seeds) if problem == "simulator" else seeds
        for n in sizes:
            for method in methods:
                rows = []
                for seed in range(args.first_seed, args.first_seed + n_seeds):
                    x = lower + (upper - lower) * qmc.LatinHypercube(d=d, seed=seed).random(n)
                    result = METHODS[method](x, func(x), lower, upper, xv, design)
                    eps = relative_errors(result.prediction, yv)
                    scored = ~np.isnan(eps)
                    rows.append((np.median(eps[scored]), np.median(result.loo[scored] / eps[scored]), result.fit_cpu,
                                 result.degree, result.predict_cpu,
                                 *sobol_errors(result.first, result.total, reference, scored)))
                eps, ratio, cpu, degree, predict_cpu, first_err, total_err = (statistics.median(c) for c in zip(*rows))
                shown = "-" if math.isnan(degree) else f"{degree:g}"
                print(f"| {problem} | {n} | {n_seeds} | {method} | {shown} | {eps:.2e} | {ratio:.2f} | {cpu:.3f} | "
                      f"{predict_cpu:.3g} | {first_err:.1e} | {total_err:.1e} |", flush=True)
    print(f"# total CPU {time.process_time() - total:.0f} s")


if __name__ == "__main__":
    main()
