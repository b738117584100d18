"""Surrogates as a plain library, in the style of scikit-learn: ``PCE``, ``GP`` and ``PCK`` estimators.

    >>> from spflow.surrogates import PCE
    >>> model = PCE(bounds=[(100, 200), (0.01, 0.02)]).fit(X, y)   # X (n, 2) in physical units, y (n,) or (n, m)
    >>> mean, std = model.predict(X_new, return_std=True)          # shaped like y
    >>> model.sobol_indices().total, model.loo_error_           # GP/PCK: Monte Carlo on the predictor, with SEs
    >>> from spflow.surrogates import Beta, LogNormal, Normal
    >>> model = PCE(inputs=[Normal(1.0, 0.2), Beta(2, 3, 0.0, 1.0), LogNormal(0.0, 0.25)]).fit(X, y)  # X from them

Each estimator takes its options in the constructor (scikit-learn's convention: ``get_params``/``set_params``/
``clone`` work, ``score`` is R²), learns from ``fit(X, y)`` and keeps the fitted surrogate of the pipeline contract
as ``model_`` (:class:`~spflow.plugins.surrogates.contract.Surrogate`: ``to_dataset()`` stores it for the stages that
``load_surrogate``). They wrap the kinds the stages fit -- :class:`~spflow.plugins.surrogates.pce_model.PCE` (thesis
§3.5), :class:`~spflow.plugins.surrogates.gp_model.GP` and :class:`~spflow.plugins.surrogates.pck_model.PCK` (§3.8)
-- with the same defaults as those functions and the stages (docs/surrogates.md, "Use as a library").

The inputs are independent, and given by exactly one of ``bounds`` (uniform on the box, one (lower, upper) pair per
input, physical units) or ``inputs`` (one marginal per input: :class:`Uniform`, :class:`Normal`, :class:`LogNormal`,
:class:`TruncatedNormal`, :class:`Beta`, :mod:`~spflow.plugins.surrogates.input_marginals`). With ``inputs`` the PCE
is built on the orthonormal family of each marginal through the isoprobabilistic transform (docs/surrogates.md,
"Input distributions"), so its moments and Sobol indices are those under these marginals; ``X`` should be drawn from
them (``marginal.sample(n, rng)``). What the API assumes about the data is recorded on ``model_``: input names
``x1..xd`` unless ``names`` is given; the marginals (``model_.inputs``, stored by ``to_dataset()``); every output
column labelled ``y`` with unit ``"1"`` (the API does not know y's unit), so ``share="variable"`` makes all columns
of a vector ``y`` share one set of Kriging length scales.

Bad input -- a wrong shape, a NaN, a point outside ``bounds`` or outside the support of a bounded marginal, both or
neither of ``bounds`` and ``inputs`` -- raises :class:`~spflow.core.errors.ParameterError` naming the argument and
the allowed range, before any fitting.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from sklearn.base import BaseEstimator, RegressorMixin

from spflow.core.errors import ParameterError
from spflow.plugins.surrogates.contract import Surrogate, input_box
from spflow.plugins.surrogates.degree_adaptive import DEGREE_MAX, MAX_TERMS_RATIO
from spflow.plugins.surrogates.input_marginals import (Beta, LogNormal, Marginal, Normal, TruncatedNormal, Uniform,
                                                     first_outside)
from spflow.plugins.surrogates.kriging_surrogate import NUGGET, RESTARTS
from spflow.plugins.surrogates.outputs import OutputIndex
from spflow.plugins.surrogates.sobol_sampling import N_BASE, REPLICATES, pick_freeze_indices

__all__ = ["PCE", "GP", "PCK", "SobolIndices", "SurrogateRegressor", "Uniform", "Normal", "LogNormal",
           "TruncatedNormal", "Beta"]


class SobolIndices(NamedTuple):
    """First-order and total Sobol indices: shape (d,) for a scalar ``y``, (m, d) for ``y`` of shape (n, m). For a
    Monte Carlo estimate (``GP``, ``PCK`` with ``part="predictor"``) ``first_se`` and ``total_se`` are their standard
    errors (same shapes); None for indices read off coefficients (exact for the model)."""

    first: np.ndarray
    total: np.ndarray
    first_se: np.ndarray | None = None
    total_se: np.ndarray | None = None


class SurrogateRegressor(RegressorMixin, BaseEstimator):
    """Common part of the estimators: input checks, ``fit``, ``predict``; subclasses build ``model_``."""

    # -- checks (before any work) -----------------------------------------------------------------------------------
    def _marginals(self) -> list[Marginal] | None:
        """``inputs`` checked (None when the inputs are given by ``bounds``); exactly one of the two must be given."""
        name = type(self).__name__
        if (self.bounds is None) == (self.inputs is None):
            raise ParameterError(f"{name}: give exactly one of bounds (uniform inputs, one (lower, upper) pair per "
                                 f"input) and inputs (one marginal distribution per input: Uniform, Normal, LogNormal,"
                                 f" TruncatedNormal, Beta), got {'both' if self.inputs is not None else 'neither'}")
        if self.inputs is None:
            return None
        inputs = list(self.inputs) if isinstance(self.inputs, (list, tuple)) else None
        if not inputs or not all(isinstance(m, Marginal) for m in inputs):
            raise ParameterError(f"{name}: inputs must be a non-empty list of marginal distributions (Uniform, Normal, "
                                 f"LogNormal, TruncatedNormal, Beta from spflow.surrogates), got {self.inputs!r}")
        return inputs

    def _box(self) -> tuple[np.ndarray, np.ndarray]:
        """(lower, upper) arrays of length d: ``bounds``, or the supports of ``inputs`` (±inf where unbounded)."""
        inputs = self._marginals()
        if inputs is not None:
            return input_box(inputs)
        name = type(self).__name__
        try:
            bounds = np.asarray(self.bounds, dtype=float)
        except (TypeError, ValueError):
            raise ParameterError(f"{name}: bounds must be numbers, one (lower, upper) pair per input; got "
                                 f"{self.bounds!r}") from None
        if bounds.ndim != 2 or bounds.shape[1] != 2 or bounds.shape[0] < 1:
            raise ParameterError(f"{name}: bounds must have shape (d, 2), one (lower, upper) pair per input; got "
                                 f"shape {bounds.shape}")
        bad = np.flatnonzero(~(np.isfinite(bounds).all(axis=1) & (bounds[:, 0] < bounds[:, 1])))
        if bad.size:
            i = int(bad[0])
            raise ParameterError(f"{name}: bounds[{i}] = [{bounds[i, 0]:g}, {bounds[i, 1]:g}] must be finite with "
                                 f"lower < upper")
        return bounds[:, 0].copy(), bounds[:, 1].copy()

    def _input_names(self, d: int) -> list[str]:
        if self.names is None:
            return [f"x{i + 1}" for i in range(d)]
        names = [str(n) for n in self.names]
        if len(names) != d or len(set(names)) != d:
            raise ParameterError(f"{type(self).__name__}: names must be {d} distinct input names (one per row of "
                                 f"bounds or entry of inputs), got {list(self.names)!r}")
        return names

    def _points(self, argument: str, X, lower: np.ndarray, upper: np.ndarray,
                inputs: list[Marginal] | None = None) -> np.ndarray:
        """``X`` as a float (n, d) array inside the box (clipped onto it within round-off), or, given ``inputs``,
        inside their supports."""
        name, d = type(self).__name__, lower.size
        try:
            X = np.asarray(X, dtype=float)
        except (TypeError, ValueError):
            raise ParameterError(f"{name}: {argument} must be a numeric array of shape (n, {d})") from None
        if X.ndim != 2 or X.shape[1] != d or X.shape[0] < 1:
            raise ParameterError(f"{name}: {argument} must have shape (n, {d}), one column per row of bounds; got "
                                 f"shape {X.shape}")
        bad = np.argwhere(~np.isfinite(X))
        if bad.size:
            i, j = map(int, bad[0])
            raise ParameterError(f"{name}: {argument}[{i}, {j}] = {X[i, j]}; {argument} must be finite, column {j} "
                                 f"in bounds[{j}] = [{lower[j]:g}, {upper[j]:g}]")
        if inputs is not None:
            outside = first_outside(inputs, X)
            if outside is not None:
                i, j = outside
                raise ParameterError(f"{name}: {argument}[{i}, {j}] = {X[i, j]:g} lies outside the support "
                                     f"{inputs[j].support_text()} of inputs[{j}] = {inputs[j]!r}")
            return np.clip(X, lower, upper)
        slack = 1e-9 * (upper - lower)
        bad = np.argwhere((X < lower - slack) | (X > upper + slack))
        if bad.size:
            i, j = map(int, bad[0])
            raise ParameterError(f"{name}: {argument}[{i}, {j}] = {X[i, j]:g} lies outside bounds[{j}] = "
                                 f"[{lower[j]:g}, {upper[j]:g}] (the surrogate's input box; it does not extrapolate)")
        return np.clip(X, lower, upper)

    # -- fitting and prediction ---------------------------------------------------------------------------------------
    def fit(self, X, y) -> SurrogateRegressor:
        """Fit on ``X`` (n, d) in physical units inside ``bounds`` (or drawn from ``inputs``) and ``y`` (n,) or (n, m);
        returns self."""
        lower, upper = self._box()
        inputs = self._marginals()
        names = self._input_names(lower.size)
        X = self._points("X", X, lower, upper, inputs)
        name = type(self).__name__
        try:
            y = np.asarray(y, dtype=float)
        except (TypeError, ValueError):
            raise ParameterError(f"{name}: y must be a numeric array of shape (n,) or (n, m)") from None
        if y.ndim not in (1, 2) or y.shape[0] != X.shape[0] or (y.ndim == 2 and y.shape[1] < 1):
            raise ParameterError(f"{name}: y must have shape (n,) or (n, m) with n = {X.shape[0]} rows (one per row "
                                 f"of X); got shape {y.shape}")
        bad = np.argwhere(~np.isfinite(y))
        if bad.size:
            where = ", ".join(map(str, bad[0]))
            raise ParameterError(f"{name}: y[{where}] = {y[tuple(bad[0])]}; y must be finite")
        columns = y.reshape(X.shape[0], -1)
        self.model_ = self._fit_model(names, lower, upper, OutputIndex.of_array(columns.shape[1]), X, columns, inputs)
        self.scalar_output_ = y.ndim == 1
        self.n_features_in_ = lower.size
        return self

    def _fit_model(self, names: list[str], lower: np.ndarray, upper: np.ndarray, outputs: OutputIndex,
                   X: np.ndarray, y: np.ndarray, inputs: list[Marginal] | None) -> Surrogate:
        """The fitted contract surrogate (subclasses); ``inputs`` None means uniform on the box."""
        raise NotImplementedError

    def _parallel(self):
        """A :class:`joblib.Parallel` for ``n_jobs`` > 1, else None."""
        if isinstance(self.n_jobs, bool) or not isinstance(self.n_jobs, (int, np.integer)) or self.n_jobs == 0:
            raise ParameterError(f"{type(self).__name__}: n_jobs must be a non-zero integer (joblib's convention: -1 "
                                 f"= all cores), got {self.n_jobs!r}")
        if self.n_jobs == 1:
            return None
        from joblib import Parallel

        return Parallel(n_jobs=self.n_jobs)

    def _fitted(self) -> Surrogate:
        if not hasattr(self, "model_"):
            raise ParameterError(f"{type(self).__name__} is not fitted yet: call fit(X, y) first")
        return self.model_

    def _per_output(self, a: np.ndarray) -> np.ndarray:
        """Per-input values (m, d) -> (d,) when ``fit`` got a scalar y."""
        return a[0] if self.scalar_output_ else a

    def _shaped(self, a: np.ndarray) -> np.ndarray:
        """(n, m) -> (n,) when ``fit`` got a scalar y; per-output (m,) -> float likewise."""
        if not self.scalar_output_:
            return a
        return a[..., 0] if a.ndim == 2 else float(a[0])

    def predict(self, X, return_std: bool = False):
        """The surrogate's mean at ``X`` (n, d) inside ``bounds``, shaped like the training ``y``; with
        ``return_std=True`` also its standard deviation (same shape). Only then is the variance computed."""
        model = self._fitted()
        X = self._points("X", X, model.lower, model.upper, None if self.inputs is None else model.inputs)
        if not return_std:
            return self._shaped(model.predict_mean(X))
        mean, variance = model.predict(X)
        return self._shaped(mean), self._shaped(np.sqrt(variance))

    @property
    def loo_error_(self):
        """Relative leave-one-out error per output, Σ e_i² / Σ (y_i − ȳ)² (thesis Eq. 3.8): a float for a scalar y,
        (m,) otherwise. See the subclass for which LOO."""
        return self._shaped(self._loo())

    def _loo(self) -> np.ndarray:
        raise NotImplementedError


class _TrendSobol:
    """``sobol_indices`` read off the orthonormal-basis coefficients of ``model_`` (its ``sobol()``)."""

    def sobol_indices(self) -> SobolIndices:
        """First and total Sobol indices under the input marginals (uniform on ``bounds``, or ``inputs``): (d,) for a
        scalar y, (m, d) otherwise."""
        ds = self._fitted().sobol()
        return SobolIndices(*(self._per_output(ds[v].values) for v in ("S1", "ST")))


class PCE(_TrendSobol, SurrogateRegressor):
    """Degree-adaptive polynomial chaos expansion (thesis §3.5, Algorithm 2) on the box ``bounds`` or under the
    marginals ``inputs`` (exactly one of them).

    Options as :func:`spflow.plugins.surrogates.degree_adaptive.fit_pce` and the ``pce`` stage: ``degree_max``
    (largest total degree tried), ``q`` (hyperbolic truncation), ``solver`` (``"ols"`` or sparse ``"lars"``),
    ``target_loo`` (stop once the corrected LOO is below it), ``max_terms_ratio`` (candidate terms per run),
    ``cv_folds`` (0, or K >= 2 for K-fold cross-validation of the whole fit as the reported error); ``n_jobs`` spreads
    the per-output LARS fits. A fit that ends at the degree cap warns
    (:class:`~spflow.core.errors.DegreeCapWarning`).

    ``predict(X, return_std=True)``'s std is the reported estimate of the proxy error, sqrt(ε · Var̂(y)), constant
    in X (a PCE has no pointwise error model). ``loo_error_`` is that ε, the estimate of the relative validation
    error: the corrected LOO ε*_LOO (Blatman & Sudret 2011) by default, the K-fold cross-validation error of the whole
    adaptive fit with ``cv_folds = K`` (``model_.info["error_estimate"]`` says which). ``sobol_indices()``: first
    and total indices from the coefficients (Sudret 2008); ``model_.moments()`` the mean and variance.
    """

    def __init__(self, bounds=None, *, inputs=None, names=None, degree_max: int = DEGREE_MAX, q: float = 0.9,
                 solver: str = "ols", target_loo: float = 0.0, max_terms_ratio: float = MAX_TERMS_RATIO,
                 cv_folds: int = 0, n_jobs: int = 1):
        self.bounds, self.inputs, self.names = bounds, inputs, names
        self.degree_max, self.q, self.solver, self.target_loo = degree_max, q, solver, target_loo
        self.max_terms_ratio, self.cv_folds, self.n_jobs = max_terms_ratio, cv_folds, n_jobs

    def _fit_model(self, names, lower, upper, outputs, X, y, inputs) -> Surrogate:
        from spflow.plugins.surrogates.pce_model import PCE as PCEModel

        return PCEModel.fit(names, lower, upper, outputs, X, y, inputs=inputs, degree_max=self.degree_max, q=self.q,
                            solver=self.solver, target_loo=self.target_loo, max_terms_ratio=self.max_terms_ratio,
                            cv_folds=self.cv_folds, parallel=self._parallel())

    def _loo(self) -> np.ndarray:
        return self._fitted().reported_error


class _Kriging(SurrogateRegressor):
    """Options common to the Kriging estimators (as ``GP.fit``/``PCK.fit`` and the ``gp``/``pck`` stages)."""

    def _kriging_options(self) -> dict:
        return {"kernel": self.kernel, "share": self.share, "nugget": self.nugget, "restarts": self.restarts,
                "seed": self.seed, "parallel": self._parallel()}

    def _loo(self) -> np.ndarray:
        return self._fitted().loo

    def _predictor_indices(self, n_base, seed, replicates) -> SobolIndices:
        """Monte Carlo first-order and total indices of the predictor mean under the input marginals, with their
        standard errors (:func:`~spflow.plugins.surrogates.sobol_sampling.pick_freeze_indices`)."""
        model = self._fitted()
        sampled = pick_freeze_indices(model.predict_mean, model.inputs, n_base=n_base, replicates=replicates,
                                      seed=seed, what=f"{type(self).__name__}.sobol_indices")
        return SobolIndices(*(self._per_output(a) for a in sampled))


class GP(_Kriging):
    """Gaussian process (ordinary Kriging, thesis §3.8 with a constant trend) on the box ``bounds``, or with the
    marginals ``inputs``: the kernel then acts on their reference variables (e.g. (x − mean)/std for a normal input;
    docs/surrogates.md, "Input distributions").

    ``kernel`` (``"gaussian"`` = squared exponential, Eq. 3.20, or ``"matern52"``), maximum-likelihood ARD length
    scales (Eq. 3.21) from ``restarts`` seeded L-BFGS-B starts, ``nugget`` on the correlation diagonal; for a vector
    ``y``, ``share="output"`` fits one model per column, ``share="variable"`` one set of length scales for all columns
    (each keeps its own mean and variance). ``n_jobs`` spreads the per-column fits. ``predict(X, return_std=True)``
    gives the Kriging standard deviation; ``loo_error_`` is the Kriging (Dubrule) LOO. ``sobol_indices()``: first
    and total indices of the predictor mean, estimated by Monte Carlo with their standard errors.
    """

    def __init__(self, bounds=None, *, inputs=None, names=None, kernel: str = "gaussian", share: str = "output",
                 nugget: float = NUGGET, restarts: int = RESTARTS, seed: int = 0, n_jobs: int = 1):
        self.bounds, self.inputs, self.names = bounds, inputs, names
        self.kernel, self.share, self.nugget, self.restarts, self.seed = kernel, share, nugget, restarts, seed
        self.n_jobs = n_jobs

    def _fit_model(self, names, lower, upper, outputs, X, y, inputs) -> Surrogate:
        from spflow.plugins.surrogates.gp_model import GP as GPModel

        return GPModel.fit(names, lower, upper, outputs, X, y, inputs=inputs, **self._kriging_options())

    def sobol_indices(self, n_base: int = N_BASE, seed: int = 0, replicates: int = REPLICATES) -> SobolIndices:
        """First-order and total Sobol indices of the predictor mean under the input marginals (uniform on
        ``bounds``, or ``inputs``): (d,) for a scalar y, (m, d) otherwise.

        A Monte Carlo estimate (a Kriging predictor has no closed-form indices): pick-freeze on ``replicates``
        (default 4) independent scramblings of a Sobol' design of ``n_base`` (default 8192, a power of 2 >= 64) base
        points mapped through the marginals' quantile functions, Saltelli et al. (2010)'s first-order and Jansen
        (1999)'s total estimator (:mod:`~spflow.plugins.surrogates.sobol_sampling`); ``seed`` (default 0) seeds the
        scramblings. The mean prediction runs at replicates (d + 2) n_base points. ``first_se``/``total_se`` are the
        standard errors of the returned mean over the replicates."""
        return self._predictor_indices(n_base, seed, replicates)


class PCK(_TrendSobol, _Kriging):
    """PC-Kriging (thesis §3.8, Eq. 3.19): universal Kriging on a sparse-PCE (hybrid LARS) trend, orthonormal under
    the box ``bounds`` (Legendre) or the marginals ``inputs``.

    ``degree_max`` and ``q`` bound the trend's PCE, ``mode`` is ``"sequential"`` (the whole LARS-selected trend) or
    ``"optimal"`` (the LOO-best LARS-ranked prefix); the Kriging options are :class:`GP`'s. ``sobol_indices()``: the
    whole predictor's indices by Monte Carlo (the default), or ``part="trend"`` the trend's, read off its
    coefficients.
    """

    def __init__(self, bounds=None, *, inputs=None, names=None, degree_max: int = 3, q: float = 0.9,
                 mode: str = "sequential", kernel: str = "gaussian", share: str = "output", nugget: float = NUGGET,
                 restarts: int = RESTARTS, seed: int = 0, n_jobs: int = 1):
        self.bounds, self.inputs, self.names = bounds, inputs, names
        self.degree_max, self.q, self.mode = degree_max, q, mode
        self.kernel, self.share, self.nugget, self.restarts, self.seed = kernel, share, nugget, restarts, seed
        self.n_jobs = n_jobs

    def _fit_model(self, names, lower, upper, outputs, X, y, inputs) -> Surrogate:
        from spflow.plugins.surrogates.pck_model import PCK as PCKModel

        return PCKModel.fit(names, lower, upper, outputs, X, y, inputs=inputs, degree_max=self.degree_max, q=self.q,
                            mode=self.mode, **self._kriging_options())

    def sobol_indices(self, part: str = "predictor", n_base: int = N_BASE, seed: int = 0,
                      replicates: int = REPLICATES) -> SobolIndices:
        """First-order and total Sobol indices under the input marginals (uniform on ``bounds``, or ``inputs``): (d,)
        for a scalar y, (m, d) otherwise.

        ``part="predictor"`` (the default): the model's own indices, those of its predictor mean (trend plus
        Gaussian-process part), estimated by Monte Carlo as :meth:`GP.sobol_indices` does (``n_base`` default 8192,
        ``replicates`` default 4, ``seed`` default 0), with their standard errors ``first_se``/``total_se``.
        ``part="trend"``: the indices of the trend alone, read off its GLS coefficients on the orthonormal basis
        (exact for the trend, no standard error; ``n_base``, ``seed``, ``replicates`` unused). The Kriging part
        σ² Z(ξ) is not in them, so they are the model's indices only where the trend carries the response."""
        if part not in ("predictor", "trend"):
            raise ParameterError(f"PCK.sobol_indices: part must be 'predictor' (the whole predictor, Monte Carlo) or "
                                 f"'trend' (the trend's coefficients), got {part!r}")
        if part == "trend":
            return super().sobol_indices()
        return self._predictor_indices(n_base, seed, replicates)
