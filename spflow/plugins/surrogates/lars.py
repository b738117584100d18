"""Hybrid least-angle regression (Blatman & Sudret 2011), UQLab's best sparse PCE solver, absent from chaospy.

The regressors are ranked by :func:`sklearn.linear_model.lars_path_gram` on the centred, unit-variance non-constant
regressors (the constant regressor is handled separately and always kept), with the LASSO modification of LARS
(Efron, Hastie, Johnstone & Tibshirani 2004, Ann. Statist. 32:407, §3.1): a regressor whose coefficient would change
sign leaves the active set, and may re-enter later. The ranking is the order of entry into the active set at the end
of the path (a regressor that left and came back ranks where it came back; one that left for good is not ranked).
"Hybrid" means that every nested model along this ranking — the constant plus the first k ranked regressors,
k = 0, 1, ... — is refitted by OLS (Eq. 3.6) and scored by its corrected (modified) LOO error (:mod:`.regression`);
the smallest nested model within one standard error of the smallest corrected LOO is selected (``prefix_rule``,
below) and its OLS coefficients returned.

Why the LASSO modification rather than plain LAR (UQLab's ``uq_lar``): plain LAR never drops a regressor, so
polynomials that entered early and became useless stay ahead of better ones in the ranking, and the nested models
must carry them. On issue #24's benchmark (``benchmarks/bench_surrogates_peers.py``, Ishigami, median of 5 LHS
designs) the LASSO ranking gave ε_val 1.6e-4 / 7.1e-8 / 1.7e-11 at N = 50 / 100 / 200 against 3.5e-2 / 3.7e-5 / 7.2e-9
for plain LAR (OpenTURNS' LARS: 0.62 / 4.7e-5 / 2.1e-11); on Borehole, the G-function and the BCF1 simulator it was
as good or better within 20 % (docs/surrogates.md, Benchmark against peers). Plain LAR stays available
(``ranking="lar"``): it is the better ranking on the G-function at N = 200-400, where the corrected LOO cannot tell
the two apart; a K-fold cross-validation of this step with the one-SE rule can (``ranking="cv"``, below), at 2.5-10
times the fit's CPU (docs/surrogates.md, "Where spflow's PCE trails OpenTURNS").

All refits come from one QR factorisation of the regressors in LARS order: with Ψ_k = Q_k R_k, the hat diagonal is
h_k = Σ_{j<=k} Q_j², the fitted values are Σ_{j<=k} Q_j (Q_jᵀ y) and tr((Ψ_kᵀΨ_k)⁻¹) = ||R_k⁻¹||²_F, all cumulative
sums over the columns, so the whole path is scored in O(N K²).

UQLab's early-stop rule is applied to the scored models: with mm = min(K, max(100, round(0.1 K))) (K = number of
ranked regressors), the search ends at the first k > mm whose best corrected LOO so far was reached at k' <= k − mm
(no improvement for mm models); the selection is the best model before that point. The path runs at most
min(N − 2, P − 1) steps, so at most that many regressors are ranked and the OLS refits always have more points than
terms.

Two options choose the model from the ranking (both measured in docs/surrogates.md, "Where spflow's PCE trails
OpenTURNS"):

* ``prefix_rule``: ``"min_loo"`` keeps the nested model with the smallest corrected LOO (the rule before issue
  #24's benchmark); ``"one_se"``, the default since then, is the one-standard-error rule (Breiman, Friedman, Olshen &
  Stone 1984, CART §3.4.3; Hastie, Tibshirani & Friedman 2009, ESL §7.10): instead of the nested model with the
  smallest corrected LOO, the smallest one (fewest terms) whose corrected LOO is within one standard error of that
  minimum. The standard error needs no refit: it is T(P*, N) times the standard error of the mean of the N squared,
  normalised LOO residuals e_i² / Var̂(y), e_i = (y_i − ŷ_i)/(1 − h_i), of the minimising model (P* terms),
  sd(e²)/√N with the N − 1 divisor. It counters the optimism of a minimum taken over many nested models by preferring fewer terms. On the
  benchmark's 60 analytic designs and the simulator it costs what the minimum costs, is at or below OpenTURNS' LARS on
  11 of 12 analytic rows (the minimum: 9) and more accurate on the simulator at N = 50, 100 and 400, and its corrected
  LOO is nearer the true error (within [0.7, 1.4] on 9 of 16 rows against 5); it is less accurate than the minimum on
  Borehole at N = 100 (3.5x, still 4x below OpenTURNS) and the G-function at N = 50 (1.25x).
* ``ranking``: ``"lasso"`` (the default) or ``"lar"`` (above), or ``"cv"``: both rankings are fitted with the same
  prefix rule, and the one with the smaller K-fold cross-validation error of this whole step (ranking, prefix choice and OLS refit redone on each
  K − 1 folds, :data:`RANKING_CV_FOLDS` folds of :func:`.folds.fold_indices`, at most one per point) is kept, per
  output (a tie keeps the LASSO ranking). The corrected LOO cannot make that choice: the LASSO path offers more
  distinct nested models, and the minimum over them is the further below the truth. Cost: 2K more LARS paths per
  output.

The factorisations are small (N x K) and run one after another, so BLAS is held to one thread inside the fits
(:mod:`.blas`); parallelism belongs one level up (over outputs).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np
from scipy.linalg import solve_triangular
from sklearn.exceptions import ConvergenceWarning
from sklearn.linear_model import lars_path_gram

from spflow.core.errors import ParameterError

from .blas import single_threaded_blas
from .folds import fold_indices
from .regression import is_constant, loo_correction, relative_errors

__all__ = ["LarsResult", "hybrid_lars", "hybrid_lars_outputs", "check_ranking", "check_prefix_rule", "PATH_SCALE",
           "RANKINGS", "RANKING_CHOICES", "PREFIX_RULES", "RANKING_CV_FOLDS"]

#: Rankings of the regressors: "lasso", the LASSO-modified LARS path (the default, above), or "lar", plain
#: least-angle regression (Efron et al. 2004, §2; UQLab's ``uq_lar`` and OpenTURNS' ``LARS``), whose regressors never
#: leave the active set, so the ranking is the order of first entry.
RANKINGS = ("lasso", "lar")
#: Values of the ``ranking`` option: one of :data:`RANKINGS`, or "cv", the one of them with the smaller K-fold
#: cross-validation error of the LARS step (module docstring).
RANKING_CHOICES = (*RANKINGS, "cv")
#: How the nested model is chosen along the ranking: "min_loo", the smallest corrected LOO, or "one_se", the
#: one-standard-error rule (the default; module docstring).
PREFIX_RULES = ("min_loo", "one_se")
#: Folds of the cross-validation behind ``ranking="cv"`` (fewer when N is smaller: one point per fold).
RANKING_CV_FOLDS = 10

#: Standard deviation the centred output is scaled to before ranking. scikit-learn ends a LARS path once the largest
#: correlation of the residual with a regressor, divided by N, is below float32's epsilon (1.2e-7) *in the units of y*:
#: unscaled, an output of standard deviation 1e-8 got no regressor at all (ε_val = 1), and Ishigami's (std 3.7) path
#: ended at a relative RMS residual of ~1e-8 (ε_val ~1e-16 at p = 18-20, where OpenTURNS reaches 1e-19). At a standard
#: deviation of 1e8 that threshold is a relative residual of ~1e-15, the round-off of y. The ranking itself does not
#: depend on the scale.
PATH_SCALE = 1e8


@dataclass(frozen=True)
class LarsResult:
    """The selected sparse model of one output.

    ``active``: column indices of Ψ in ranking order (above), constant first; ``coefficients``: (P,), zero outside
    ``active``; ``loo``/``modified_loo``/``empirical``: errors of the OLS refit on ``active``; ``path_modified_loo``:
    the corrected LOO of every scored nested model (index k = constant + k regressors), up to the early stop;
    ``ranking``: the ranking of :data:`RANKINGS` the model comes from (with ``ranking="cv"``, the one chosen).
    """

    active: np.ndarray
    coefficients: np.ndarray
    loo: float
    modified_loo: float
    empirical: float
    path_modified_loo: np.ndarray
    ranking: str


class _Regressors:
    """Ψ's constant column and its centred, unit-variance other columns with their Gram matrix (shared by outputs)."""

    def __init__(self, psi: np.ndarray):
        psi = np.ascontiguousarray(psi, dtype=float)
        if psi.ndim != 2 or psi.shape[0] < 3:
            raise ParameterError(f"hybrid_lars: psi must be (N, P) with N >= 3, got shape {psi.shape}")
        if not np.isfinite(psi).all():
            raise ParameterError("hybrid_lars: psi must be finite")
        constant = np.flatnonzero(np.ptp(psi, axis=0) == 0.0)
        constant = constant[psi[0, constant] != 0.0]
        if constant.size == 0:
            raise ParameterError("hybrid_lars: psi needs a non-zero constant column (the PCE's Ψ_0 = 1)")
        self.psi = psi
        self.constant = int(constant[0])
        centred = psi - psi.mean(axis=0)
        scale = np.sqrt(np.sum(centred**2, axis=0) / (psi.shape[0] - 1))
        # candidates: non-constant columns (constant ones centre to zero and can never enter)
        self.candidates = np.flatnonzero(scale > 0.0)
        x = centred[:, self.candidates] / scale[self.candidates]
        self.x = x
        self.gram = x.T @ x
        self.max_steps = int(min(psi.shape[0] - 2, self.candidates.size))

    def path(self, y: np.ndarray, ranking: str) -> np.ndarray:
        """Columns of Ψ ranked by entry into the final active set of the LASSO-LARS (``ranking`` "lasso") or plain LAR
        ("lar") path (at most ``max_steps`` path steps)."""
        if self.max_steps == 0 or is_constant(y[:, None])[0]:
            return np.zeros(0, dtype=np.int64)
        yc = y - y.mean()
        yc *= PATH_SCALE / yc.std()  # the path's stopping threshold is absolute (PATH_SCALE)
        with warnings.catch_warnings():
            # the path stops by itself once the residual is numerically zero (exact fit); that is not an error here
            warnings.simplefilter("ignore", ConvergenceWarning)
            _, active, _ = lars_path_gram(self.x.T @ yc, self.gram, n_samples=self.x.shape[0],
                                          max_iter=self.max_steps, method=ranking)
        return self.candidates[np.asarray(active, dtype=np.int64)]

    def fit(self, y: np.ndarray, ranking: str, prefix_rule: str) -> LarsResult:
        order = np.concatenate([[self.constant], self.path(y, ranking)]).astype(np.int64)
        q, r = np.linalg.qr(self.psi[:, order])
        diag = np.abs(np.diag(r))
        # a regressor numerically dependent on the earlier ones ends the usable path
        dependent = np.flatnonzero(diag < 1e-10 * diag.max())
        usable = int(dependent[0]) if dependent.size else order.size
        q, r, order = q[:, :usable], r[:usable, :usable], order[:usable]
        qy = q.T @ y
        fitted = np.cumsum(q * qy, axis=1)
        leverage = np.cumsum(q**2, axis=1)
        emp, loo = relative_errors(y[:, None], y[:, None] - fitted, leverage)
        r_inv = solve_triangular(r, np.eye(usable))
        trace = np.cumsum(np.sum(r_inv**2, axis=0))
        # at most N - 1 terms, so every correction T(k + 1, N) is finite
        t = np.array([loo_correction(y.size, k + 1, trace[k]) for k in range(usable)])
        modified = (t * loo)[: _early_stop(t * loo)]
        best = int(np.argmin(modified))
        if prefix_rule == "one_se":
            with np.errstate(divide="ignore", invalid="ignore"):
                squared = ((y - fitted[:, best]) / (1.0 - leverage[:, best])) ** 2 / y.var()
                threshold = modified[best] + t[best] * np.std(squared, ddof=1) / np.sqrt(y.size)
            if np.isfinite(threshold):  # not for a constant output (Var̂ = 0) or an interpolated point (h = 1)
                best = int(np.flatnonzero(modified <= threshold)[0])
        coef = np.zeros(self.psi.shape[1])
        coef[order[: best + 1]] = solve_triangular(r[: best + 1, : best + 1], qy[: best + 1])
        return LarsResult(order[: best + 1], coef, float(loo[best]), float(modified[best]), float(emp[best]),
                          modified, ranking)


def _rankings_by_cv(psi: np.ndarray, y: np.ndarray, prefix_rule: str) -> list[str]:
    """Per column of ``y`` (N, m): the ranking of :data:`RANKINGS` whose LARS step (with ``prefix_rule``) has the
    smaller K-fold cross-validation error (module docstring); the regressors of a fold are shared by the outputs."""
    squared = np.zeros((len(RANKINGS), y.shape[1]))
    for held in fold_indices(y.shape[0], min(RANKING_CV_FOLDS, y.shape[0])):
        train = np.setdiff1d(np.arange(y.shape[0]), held)
        regressors = _Regressors(psi[train])
        for i, ranking in enumerate(RANKINGS):
            for j in range(y.shape[1]):
                fit = regressors.fit(np.ascontiguousarray(y[train, j]), ranking, prefix_rule)
                squared[i, j] += np.sum((psi[held] @ fit.coefficients - y[held, j]) ** 2)
    return [RANKINGS[int(i)] for i in np.argmin(squared, axis=0)]  # argmin: a tie keeps the first, LASSO


def _early_stop(scores: np.ndarray) -> int:
    """Number of leading nested models kept by UQLab's rule (no improvement over the last mm models)."""
    steps = scores.size - 1  # step 0 is the constant-only model
    mm = min(steps, max(100, round(0.1 * steps)))
    step = np.arange(scores.size)
    new_best = np.concatenate([[True], scores[1:] < np.minimum.accumulate(scores)[:-1]])
    best_at = np.maximum.accumulate(np.where(new_best, step, 0))
    stop = np.flatnonzero((step > mm) & (best_at <= step - mm))
    return int(stop[0]) + 1 if stop.size else scores.size


def _check_y(y: np.ndarray, n: int, ndim: int) -> np.ndarray:
    y = np.asarray(y, dtype=float)
    if y.ndim != ndim or y.shape[0] != n:
        shape = "(N,)" if ndim == 1 else "(N, m)"
        raise ParameterError(f"hybrid_lars: y must have shape {shape} with N = {n} rows, got {y.shape}")
    if not np.isfinite(y).all():
        raise ParameterError("hybrid_lars: y must be finite")
    return y


def check_ranking(ranking, where: str) -> None:
    """``ranking`` must be one of :data:`RANKING_CHOICES`; ``where`` names the caller in the error."""
    if ranking not in RANKING_CHOICES:
        raise ParameterError(f"{where}: ranking must be one of {RANKING_CHOICES} (LASSO-modified LARS, plain LAR, or "
                             f"the one of the two a {RANKING_CV_FOLDS}-fold cross-validation prefers), got {ranking!r}")


def check_prefix_rule(prefix_rule, where: str) -> None:
    """``prefix_rule`` must be one of :data:`PREFIX_RULES`; ``where`` names the caller in the error."""
    if prefix_rule not in PREFIX_RULES:
        raise ParameterError(f"{where}: prefix_rule must be one of {PREFIX_RULES} (the smallest corrected LOO, or "
                             f"the one-standard-error rule), got {prefix_rule!r}")


def _fit_outputs(psi: np.ndarray, y: np.ndarray, ranking: str, prefix_rule: str, ndim: int) -> list[LarsResult]:
    """The checked options and data, then one hybrid LARS per column of ``y`` ((N,) for ``ndim`` 1, else (N, m))."""
    check_ranking(ranking, "hybrid_lars")
    check_prefix_rule(prefix_rule, "hybrid_lars")
    regressors = _Regressors(psi)
    y = _check_y(y, regressors.psi.shape[0], ndim).reshape(regressors.psi.shape[0], -1)
    if ranking == "cv" and y.shape[0] < 4:
        raise ParameterError(f"hybrid_lars: ranking 'cv' needs N >= 4 points (at least 3 in each fold's fit), got "
                             f"N = {y.shape[0]}")
    with single_threaded_blas():
        rankings = _rankings_by_cv(regressors.psi, y, prefix_rule) if ranking == "cv" else [ranking] * y.shape[1]
        return [regressors.fit(np.ascontiguousarray(y[:, j]), rankings[j], prefix_rule) for j in range(y.shape[1])]


def hybrid_lars(psi: np.ndarray, y: np.ndarray, ranking: str = "lasso", prefix_rule: str = "one_se") -> LarsResult:
    """Hybrid LARS of one output ``y`` (N,) on the regressors ``psi`` (N, P) (one column must be constant), the
    regressors ranked by ``ranking`` (:data:`RANKING_CHOICES`), the nested model chosen by ``prefix_rule``
    (:data:`PREFIX_RULES`)."""
    return _fit_outputs(psi, y, ranking, prefix_rule, 1)[0]


def hybrid_lars_outputs(psi: np.ndarray, y: np.ndarray, ranking: str = "lasso",
                        prefix_rule: str = "one_se") -> list[LarsResult]:
    """One independent hybrid LARS per column of ``y`` (N, m) (UQLab's treatment of vector outputs); the centred
    regressors and their Gram matrix are computed once (per fold, too, with ``ranking="cv"``)."""
    return _fit_outputs(psi, y, ranking, prefix_rule, 2)
