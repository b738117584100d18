"""Degree- and q-norm-adaptive PCE fit (UQLab's regression loop; thesis Algorithm 2 lines 6-8).

For p = 1, 2, ... and each q of the list, the q-norm basis A(p, q) (:mod:`.basis`, one orthonormal family per input) is
fitted by OLS (:mod:`.regression`) or hybrid LARS (:mod:`.lars`) and scored by its corrected (modified) leave-one-out
error ε*_LOO = T(P, N) ε_LOO, T(P, N) = N/(N − P) · (1 + tr(C_emp⁻¹)/N) with C_emp = ΨᵀΨ/N the empirical information
matrix of the P selected terms (Blatman & Sudret 2011, J. Comput. Phys. 230:2345, after Chapelle, Vapnik & Bengio 2002;
UQLab PCE manual Eqs. 1.22-1.23). Vector outputs (the 0.1 PV time series of a QoI) share one basis: the score of a basis
is ε^mean, the mean over outputs of ε*_LOO (Eq. 3.9 applied to the corrected LOO), and the basis with the smallest
ε^mean wins. With OLS every output then has coefficients on the whole of A(p, q); with LARS each output keeps its own
sparse support inside it (zeros elsewhere), as UQLab fits one sparse PCE per output component.

Stopping rules (UQLab defaults):

* q loop (inner): a q giving the same number of terms as the previous q is skipped; the loop ends when the last two
  q values did not improve on the best q of this degree;
* degree loop (outer, ``early_stop``): ends when the last two degrees both failed to improve on the best so far (a
  tie counts as no improvement: LARS often selects the same terms from a larger basis, and without this rule the
  search would walk to the cap on ties);
* target accuracy: ends as soon as the best ε^mean <= ``target_loo``, or <= :data:`EXACT_FIT` (1e-20, a relative
  RMS error of 1e-10): an exact fit, whose further "improvements" are round-off and would otherwise carry the search
  to the cap;
* the cap: ``degree_max`` (default 20, the largest allowed), and no basis with more than
  max(``max_terms_ratio`` · N, :data:`MIN_TERMS`) candidate terms is built (defaults 10 and 1000: LARS's Gram matrix
  grows as the square of the basis, and a candidate set ten times the number of runs already leaves LARS most of the
  degree's terms to choose from; below 1000 terms the cost is a few milliseconds and the limit would only cut small
  designs short — on the 8-D G-function at N = 50 it kept p <= 4, ε_val 0.18 against 0.11 at p = 5); the degree
  loop ends at the first degree all of whose bases exceed it. When the selected degree is the largest one the cap
  let the search try, the data may have asked for more: a :class:`~spflow.core.errors.DegreeCapWarning` says so and :attr:`PCEFit.cap_warning` keeps
  the message (the ``pce`` stage stores it in ``attrs["degree_cap_warning"]``).

The thesis capped the degree at 5; that default stalled on smooth but strongly non-linear responses (issue #24:
Ishigami ε_val ≈ 0.25 at every N), so the search now goes on while the corrected LOO improves. A cap of 15 still held
Ishigami at the truncation error of a degree-15 sine expansion (ε_val ≈ 1.4e-11 at N = 400); with 20 it reaches
8.9e-20, and on the 8- and 9-input benchmark problems the basis-size limit binds first (p <= 7), so 20 changes
nothing there (docs/surrogates.md, Benchmark against peers).

OLS needs more points than terms (otherwise T(P, N) = ∞, :func:`.regression.loo_correction`), so such bases score ∞
without being fitted. The fits run on one BLAS thread (:mod:`.blas`; the matrices are at most a few thousand rows).
"""

from __future__ import annotations

import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np

from spflow.core.errors import DegreeCapWarning, ParameterError

from .blas import single_threaded_blas
from .orthonormal_polynomials import LEGENDRE, PolynomialFamily
from .regression import ols

__all__ = ["PCEFit", "fit_pce", "SOLVERS", "DEGREE_MAX", "MAX_TERMS_RATIO", "MIN_TERMS", "EXACT_FIT"]

SOLVERS = ("ols", "lars")
#: Default largest total degree tried (the ``pce`` stages share it).
DEGREE_MAX = 20
#: Default largest candidate basis, in terms per training run.
MAX_TERMS_RATIO = 10.0
#: The basis-size limit never goes below this many candidate terms.
MIN_TERMS = 1000
#: ε^mean at or below which a fit is exact (round-off) and the degree search stops.
EXACT_FIT = 1e-20


@dataclass(frozen=True)
class PCEFit:
    """The selected expansion: ``indices`` (P, d), ``coefficients`` (m, P), per-output errors (m,) and the training
    outputs' population variance (m,); ``history`` lists (degree, q, n_terms, ε^mean) of every scored basis;
    ``degree_cap`` is the largest degree the search could try (``degree_max`` or the basis-size limit) and
    ``cap_warning`` the message of the :class:`~spflow.core.errors.DegreeCapWarning` ("" when the selected degree is
    below the cap or the search stopped on its own); ``rankings`` the LARS ranking of each output's model (with
    ``ranking="cv"``, the one chosen; empty for OLS)."""

    indices: np.ndarray
    coefficients: np.ndarray
    degree: int
    q: float
    solver: str
    loo: np.ndarray
    modified_loo: np.ndarray
    empirical: np.ndarray
    output_variance: np.ndarray
    history: list[tuple[int, float, int, float]] = field(default_factory=list)
    degree_cap: int = DEGREE_MAX
    cap_warning: str = ""
    rankings: tuple[str, ...] = ()

    @property
    def loo_mean(self) -> float:
        """ε_LOO^mean (Eq. 3.9)."""
        return float(np.mean(self.loo))

    @property
    def modified_loo_mean(self) -> float:
        """Mean corrected (modified) LOO of the selected models over outputs: the selection score, except with
        ``prefix_rule="one_se"`` or ``ranking="cv"``, whose models are not the minimum of the path (the score of their
        basis is in ``history``)."""
        return float(np.mean(self.modified_loo))

    @property
    def empirical_mean(self) -> float:
        """ε_emp^mean (Eq. 3.10)."""
        return float(np.mean(self.empirical))


def _fit_basis(psi: np.ndarray, y: np.ndarray, solver: str, ranking: str, prefix_rule: str,
               parallel) -> tuple[np.ndarray, ...]:
    """(coefficients (m, P), loo, modified_loo, empirical, score, rankings) of one basis. ``score`` (m,) is what the
    degree search compares: the smallest corrected LOO along each output's LARS path (the selected model's for
    ``prefix_rule="min_loo"``) or the OLS fit's; ``rankings`` the ranking each output's LARS model comes from (empty for
    OLS)."""
    from .lars import hybrid_lars_outputs  # scikit-learn loads when a PCE is fitted

    if solver == "ols":
        if psi.shape[0] <= psi.shape[1]:
            inf = np.full(y.shape[1], np.inf)
            return np.zeros((y.shape[1], psi.shape[1])), inf, inf, inf, inf, ()
        fit = ols(psi, y)
        return fit.coefficients.T, fit.loo, fit.modified_loo, fit.empirical, fit.modified_loo, ()
    if parallel is None or y.shape[1] == 1:
        results = hybrid_lars_outputs(psi, y, ranking, prefix_rule)
    else:
        from joblib import delayed

        chunks = np.array_split(np.arange(y.shape[1]), min(y.shape[1], max(1, parallel.n_jobs)))
        parts = parallel(delayed(hybrid_lars_outputs)(psi, y[:, c], ranking, prefix_rule) for c in chunks)
        results = [r for part in parts for r in part]
    return (np.array([r.coefficients for r in results]), np.array([r.loo for r in results]),
            np.array([r.modified_loo for r in results]), np.array([r.empirical for r in results]),
            np.array([r.path_modified_loo.min() for r in results]), tuple(r.ranking for r in results))


def _check(z: np.ndarray, y: np.ndarray, degree_max: int, q: Sequence[float], solver: str, target_loo,
           max_terms_ratio, families):
    if z.ndim != 2 or y.ndim != 2 or z.shape[0] != y.shape[0]:
        raise ParameterError(f"fit_pce: need z (N, d) and y (N,) or (N, m) with the same N; got z {z.shape}, "
                             f"y {y.shape}")
    if z.shape[0] < 3:
        raise ParameterError(f"fit_pce: need at least 3 training points, got {z.shape[0]}")
    if not (np.isfinite(z).all() and np.isfinite(y).all()):
        raise ParameterError("fit_pce: z and y must be finite")
    if families is not None and len(families) != z.shape[1]:
        raise ParameterError(f"fit_pce: need one polynomial family per column of z ({z.shape[1]}), got "
                             f"{len(families)}")
    for k, family in enumerate(families or [LEGENDRE] * z.shape[1]):
        lo, hi = family.support
        slack = 1e-9 * (hi - lo) if np.isfinite(hi - lo) else 0.0
        if ((z[:, k] < lo - slack) | (z[:, k] > hi + slack)).any():
            raise ParameterError(f"fit_pce: z[:, {k}] must lie in the support [{lo:g}, {hi:g}] of its {family.name} "
                                 f"polynomials (for uniform inputs, the unit box [-1, 1]^d: map physical points with "
                                 f"to_unit)")
    if isinstance(degree_max, bool) or not isinstance(degree_max, (int, np.integer)) or not 1 <= degree_max <= 20:
        raise ParameterError(f"fit_pce: degree_max must be an integer in [1, 20], got {degree_max!r}")
    if not q or any(not 0.0 < float(v) <= 1.0 for v in q):
        raise ParameterError(f"fit_pce: every q-norm must be in (0, 1], got {list(q)}")
    if solver not in SOLVERS:
        raise ParameterError(f"fit_pce: solver must be one of {SOLVERS}, got {solver!r}")
    if isinstance(max_terms_ratio, bool) or not isinstance(max_terms_ratio, (int, float, np.number)) \
            or not max_terms_ratio >= 1.0 or not np.isfinite(max_terms_ratio):
        raise ParameterError(f"fit_pce: max_terms_ratio must be a finite number >= 1 (candidate terms per training "
                             f"run), got {max_terms_ratio!r}")
    if target_loo is not None and not target_loo >= 0.0:
        raise ParameterError(f"fit_pce: target_loo must be >= 0 or None, got {target_loo!r}")
    if solver == "ols" and z.shape[0] <= z.shape[1] + 1:
        raise ParameterError(f"fit_pce: least squares (solver 'ols') needs more training runs than the degree-1 basis "
                             f"has terms: N = {z.shape[0]} <= d + 1 = {z.shape[1] + 1} leaves no leave-one-out error; "
                             f"add runs or use solver 'lars'")


def fit_pce(z: np.ndarray, y: np.ndarray, degree_max: int = DEGREE_MAX, q: float | Sequence[float] = 0.9,
            solver: str = "ols", target_loo: float | None = 0.0, early_stop: bool = True,
            max_terms_ratio: float = MAX_TERMS_RATIO, parallel=None,
            progress: Callable[[int, int], None] | None = None,
            families: Sequence[PolynomialFamily] | None = None, ranking: str = "lasso",
            prefix_rule: str = "one_se") -> PCEFit:
    """Fit a PCE of ``y`` (N,) or (N, m) at reference points ``z`` (N, d), choosing degree and q as above.

    ``families`` gives each coordinate's orthonormal family (:mod:`.orthonormal_polynomials`); None means Legendre
    for all, z in [-1, 1]^d. ``ranking`` ("lasso", "lar" or "cv", :data:`.lars.RANKING_CHOICES`) is how the LARS
    solver ranks the regressors: the LASSO-modified path (default), plain LAR, or per output the one of the two with
    the smaller 10-fold cross-validation error of the LARS step; ``prefix_rule`` ("min_loo" or "one_se",
    :data:`.lars.PREFIX_RULES`) how it chooses the nested model along the ranking: the smallest corrected LOO
    or the one-standard-error rule (default) (:mod:`.lars`; docs/surrogates.md, "Where spflow's PCE trails
    OpenTURNS"). The degree and q search always scores a basis by the smallest corrected LOO along a ranking (the
    LASSO one for "cv"), whatever model the prefix rule keeps (scored by its one-SE model, the search stopped
    Ishigami at N = 50 at degree 1); the cross-validated choice of the ranking is made on the selected basis only.
    Both options are ignored by OLS.

    ``parallel`` (a :class:`joblib.Parallel`, e.g. ``ctx.parallel()``) spreads the per-output LARS fits over workers;
    ``progress(degree, degree_max)`` (e.g. from ``ctx.report_progress``) is told each degree tried, and
    ``(degree_max, degree_max)`` at the end. Warns (:class:`~spflow.core.errors.DegreeCapWarning`) when the selected
    degree is the cap.
    """
    from .basis import design_matrix, multi_indices  # numba/numpoly load when a PCE is fitted
    from .lars import check_prefix_rule, check_ranking  # scikit-learn loads when a PCE is fitted

    z = np.atleast_2d(np.asarray(z, dtype=float))
    y = np.asarray(y, dtype=float)
    y = y[:, None] if y.ndim == 1 else y
    qs = [float(v) for v in (q if isinstance(q, Sequence) else [q])]
    _check(z, y, degree_max, qs, solver, target_loo, max_terms_ratio, families)
    check_ranking(ranking, "fit_pce")
    check_prefix_rule(prefix_rule, "fit_pce")
    if solver == "lars" and ranking == "cv" and z.shape[0] < 4:
        raise ParameterError(f"fit_pce: ranking 'cv' needs N >= 4 training runs, got {z.shape[0]}")
    search_ranking = "lasso" if ranking == "cv" else ranking
    max_terms = max(int(max_terms_ratio * z.shape[0]), MIN_TERMS)
    history: list[tuple[int, float, int, float]] = []
    best, best_score, degree_scores = None, np.inf, []
    stopped, cap = False, degree_max
    for degree in range(1, degree_max + 1):
        degree_best, q_scores, last_size, too_big = np.inf, [], -1, []
        for qv in qs:
            indices = multi_indices(z.shape[1], degree, qv)
            if indices.shape[0] == last_size:
                continue
            last_size = indices.shape[0]
            if indices.shape[0] > max_terms and degree > 1:  # degree 1 (d + 1 terms) is always tried
                too_big.append(indices.shape[0])
                continue
            with single_threaded_blas():
                coef, loo, modified, emp, scores, rankings = _fit_basis(design_matrix(z, indices, families), y,
                                                                        solver, search_ranking, prefix_rule, parallel)
            score = float(np.mean(scores))
            history.append((degree, qv, indices.shape[0], score))
            q_scores.append(score)
            degree_best = min(degree_best, score)
            if score < best_score or best is None:
                best_score = score
                best = (indices, coef, degree, qv, loo, modified, emp, rankings)
            if len(q_scores) > 2 and min(q_scores[-2:]) >= min(q_scores[:-2]):
                break
        if not q_scores:  # every basis of this degree is over the size limit
            cap = degree - 1
            break
        degree_scores.append(degree_best)
        if progress is not None and degree < degree_max:
            progress(degree, degree_max)
        if best_score <= max(EXACT_FIT, target_loo or 0.0):
            stopped = True
            break
        if early_stop and len(degree_scores) > 2 and min(degree_scores[-2:]) >= min(degree_scores[:-2]):
            stopped = True
            break
    if progress is not None:  # done, whether at degree_max or stopped early
        progress(degree_max, degree_max)
    indices, coef, degree, qv, loo, modified, emp, rankings = best
    if solver == "lars" and ranking == "cv":
        with single_threaded_blas():
            coef, loo, modified, emp, _, rankings = _fit_basis(design_matrix(z, indices, families), y, solver,
                                                               ranking, prefix_rule, parallel)
    message = ""
    if not stopped and degree == cap:
        reason = (f"degree_max = {degree_max}" if cap == degree_max else
                  f"the basis-size limit: degree {cap + 1} needs {min(too_big)} candidate terms > "
                  f"max(max_terms_ratio × N, {MIN_TERMS}) = {max_terms}")
        message = (f"fit_pce: the selected degree {degree} is the largest the search could try ({reason}) and the "
                   f"corrected LOO error was still falling; a higher degree may fit better: raise degree_max, "
                   f"max_terms_ratio or the number of runs")
        warnings.warn(message, DegreeCapWarning, stacklevel=2)
    return PCEFit(indices, coef, degree, qv, solver, loo, modified, emp, y.var(axis=0), history, cap, message,
                  rankings)
