"""The ``pce`` surrogate kind: a polynomial chaos expansion on the orthonormal basis of its inputs' marginals (thesis
Eq. 3.4): Legendre for uniform inputs, Hermite for normal and lognormal ones, Jacobi for beta ones, Stieltjes
polynomials of the truncated normal for truncated normal ones (:mod:`.input_marginals`).

Stored as arrays, no pickle: ``coefficients`` (output, term), ``multi_index`` (term, param), the per-output errors
(``loo``, ``modified_loo``, ``empirical``; Eqs. 3.7-3.8, and ``cv_error`` when the fit was cross-validated) and the
training outputs' population variance.

Prediction: the mean is Σ_α y_α Ψ_α(z) at the reference point z = :meth:`to_unit` (x). The variance returned by
:meth:`predict` is the reported estimate of the proxy's squared error, :attr:`PCE.reported_error` · Var̂(y), per
output and constant in x — a PCE has no pointwise error model, and this is the number calibration adds to a
likelihood's noise variance (docs/surrogates.md, The model; docs/calibration.md, The posterior). By default
(``cv_folds = 0``) it is the corrected LOO, ε*_LOO · Var̂(y) = T(P, N) (1/N) Σ_i (e_i / (1 − h_i))² with
T(P, N) = N/(N − P) · (1 + tr(C_emp⁻¹)/N) (Blatman & Sudret 2011, :mod:`.degree_adaptive`); with ``cv_folds = K``
>= 2 it is the K-fold cross-validation error of the whole adaptive fit (:mod:`.pce_cross_validation`), which has not
seen its own selection but costs K fits and errs high where the error falls fast with N. The plain LOO underestimates
the error of a LARS-selected basis (the selection has seen every point; issue #24 measured 1.5-4x at N <= 100); the
corrected one less so (0.45-0.75 of the validation error on the G-function and the simulator, docs/surrogates.md).
Moments (Eqs. 3.11-3.12) and Sobol indices come from the
coefficients (:mod:`.sobol_from_pce`), never from chaospy's symbolic ``Var``/``Sens_*``.
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from spflow.core.cf_metadata import UNITS_VARIABLE

from spflow.core.errors import ParameterError

from . import sobol_from_pce as sobol
from .blas import single_threaded_blas
from .contract import Surrogate, reference_points, resolve_inputs
from .degree_adaptive import PCEFit, fit_pce
from .input_marginals import check_support
from .pce_cross_validation import check_folds, kfold_error
from .outputs import OutputIndex

__all__ = ["PCE"]

#: Points per block in :meth:`PCE._predict` (keeps each block of Ψ in cache between its construction and its use;
#: the blocks' products run on one BLAS thread, :mod:`.blas`).
_BLOCK = 512


class PCE(Surrogate):
    """Polynomial chaos expansion; build with :meth:`fit` (or the ``pce`` / ``adaptive_pce`` stages)."""

    kind = "pce"

    def __init__(self, names: list[str], lower: np.ndarray, upper: np.ndarray, outputs: OutputIndex,
                 indices: np.ndarray, coefficients: np.ndarray, loo: np.ndarray, modified_loo: np.ndarray,
                 empirical: np.ndarray, output_variance: np.ndarray, info: dict, inputs=None, input_note: str = "",
                 cv_error: np.ndarray | None = None):
        super().__init__(names, lower, upper, outputs, inputs, input_note)
        self.indices = np.ascontiguousarray(indices, dtype=np.int64)
        self.coefficients = np.ascontiguousarray(coefficients, dtype=float)
        self.loo, self.modified_loo = np.asarray(loo, dtype=float), np.asarray(modified_loo, dtype=float)
        self.empirical, self.output_variance = np.asarray(empirical, dtype=float), np.asarray(output_variance, float)
        self.cv_error = None if cv_error is None else np.asarray(cv_error, dtype=float)
        self.info = {"cv_folds": 0, **info}
        self.info["error_estimate"] = "corrected_loo" if self.cv_error is None else "kfold_cv"
        d, m = len(self.names), len(outputs)
        if self.indices.ndim != 2 or self.indices.shape[1] != d:
            raise ParameterError(f"PCE: multi-indices must be (term, {d}) for parameters {self.names}, got "
                                 f"{self.indices.shape}")
        if self.coefficients.shape != (m, self.indices.shape[0]):
            raise ParameterError(f"PCE: coefficients must be (output, term) = ({m}, {self.indices.shape[0]}), got "
                                 f"{self.coefficients.shape}")
        errors = (self.loo, self.modified_loo, self.empirical, self.output_variance)
        if any(a.shape != (m,) for a in errors + (() if self.cv_error is None else (self.cv_error,))):
            raise ParameterError(f"PCE: per-output errors must have length {m}")

    @classmethod
    def fit(cls, names: list[str], lower: np.ndarray, upper: np.ndarray, outputs: OutputIndex, x: np.ndarray,
            y: np.ndarray, *, inputs=None, **options) -> PCE:
        """Fit on points ``x`` (N, d) in physical units and outputs ``y`` (N, m). The inputs are uniform on the box
        unless ``inputs`` gives one marginal per parameter (:mod:`.input_marginals`; then ``lower``/``upper`` are
        their supports, :func:`.contract.input_box`), and ``x`` should be drawn from them: the coefficients are a
        least-squares projection under the empirical measure of ``x``. ``options`` go to
        :func:`.degree_adaptive.fit_pce` (``degree_max``, ``q``, ``solver``, ``target_loo``, ``parallel``, ``ranking``,
        ``prefix_rule``...), except ``cv_folds`` (default 0): K >= 2 also cross-validates the whole fit K-fold
        (:mod:`.pce_cross_validation`, about K times the fit's cost), and that error is then the one reported
        (:attr:`reported_error`)."""
        marginals = resolve_inputs(names, lower, upper, inputs, "PCE.fit")
        x = np.atleast_2d(np.asarray(x, dtype=float))
        if x.shape[1] != len(names):
            raise ParameterError(f"PCE.fit: x must have one column per parameter {list(names)}, got shape {x.shape}")
        y = np.asarray(y, dtype=float).reshape(x.shape[0], -1)
        folds = options.pop("cv_folds", 0)
        check_folds(folds, x.shape[0], x.shape[1], options.get("solver", "ols"), "PCE.fit")
        if y.shape[1] != len(outputs):
            raise ParameterError(f"PCE.fit: y has {y.shape[1]} columns for {len(outputs)} outputs")
        if inputs is not None:
            if not np.isfinite(x).all():
                raise ParameterError("PCE.fit: training x must be finite")
            check_support(marginals, names, x, "PCE.fit: training x")
        z, families = reference_points(marginals, x), [m.polynomials for m in marginals]
        result = fit_pce(z, y, families=families, **options)
        cv = None
        if folds:
            options.pop("progress", None)
            cv = kfold_error(z, y, folds, families=families, **options)
        return cls.from_fit(names, lower, upper, outputs, result, n_train=x.shape[0], inputs=inputs, cv_error=cv,
                            cv_folds=folds)

    @classmethod
    def from_fit(cls, names, lower, upper, outputs, result: PCEFit, n_train: int, inputs=None,
                 cv_error: np.ndarray | None = None, cv_folds: int = 0) -> PCE:
        info = {"degree": result.degree, "q": result.q, "solver": result.solver, "n_train": n_train,
                "degree_cap": result.degree_cap, "degree_cap_warning": result.cap_warning, "cv_folds": int(cv_folds)}
        return cls(names, lower, upper, outputs, result.indices, result.coefficients, result.loo,
                   result.modified_loo, result.empirical, result.output_variance, info, inputs, cv_error=cv_error)

    # -- prediction ---------------------------------------------------------------------------------------------
    @property
    def reported_error(self) -> np.ndarray:
        """The relative error the model reports, per output: the K-fold cross-validation error of the whole fit when
        it was computed (``info["error_estimate"]`` "kfold_cv"), else the corrected LOO ε*_LOO ("corrected_loo")."""
        return self.modified_loo if self.cv_error is None else self.cv_error

    @property
    def error_variance(self) -> np.ndarray:
        """Per-output estimate of the proxy's squared error, :attr:`reported_error` · Var̂(y)."""
        return self.reported_error * self.output_variance

    def _predict(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        from .basis import design_matrix  # numba: on first prediction

        z = self.to_unit(x)
        mean = np.empty((z.shape[0], self.coefficients.shape[0]))
        coef_t = self.coefficients.T
        with single_threaded_blas(z.shape[0] * coef_t.size):
            for start in range(0, z.shape[0], _BLOCK):
                stop = min(start + _BLOCK, z.shape[0])
                np.matmul(design_matrix(z[start:stop], self.indices, self.families), coef_t, out=mean[start:stop])
        return mean, np.broadcast_to(self.error_variance, mean.shape).copy()

    # -- statistics from the coefficients -----------------------------------------------------------------------
    def moments(self) -> tuple[np.ndarray, np.ndarray]:
        """Mean and variance of every output under the input marginals (Eqs. 3.11-3.12; the basis is orthonormal
        under them, whatever the families)."""
        return sobol.moments(self.indices, self.coefficients)

    def sobol(self) -> xr.Dataset:
        """First-order and total Sobol indices, dims (output, param)."""
        return sobol.sobol_dataset(self.names, self.outputs, self.indices, self.coefficients)

    def group_sobol(self, params: list[str], closed: bool = False) -> np.ndarray:
        """Interaction (or closed) Sobol index of a group of parameters, per output."""
        unknown = [p for p in params if p not in self.names]
        if unknown:
            raise ParameterError(f"PCE.group_sobol: unknown parameter {unknown[0]!r}; parameters: {self.names}")
        return sobol.group_index(self.indices, self.coefficients, [self.names.index(p) for p in params], closed)

    # -- storage ------------------------------------------------------------------------------------------------
    def to_dataset(self) -> xr.Dataset:
        what = {"loo": "relative leave-one-out error (Eq. 3.8)", "modified_loo": "corrected leave-one-out error",
                "empirical": "relative empirical error (Eq. 3.10)",
                "cv_error": "relative K-fold cross-validation error of the whole adaptive fit"}
        errors = {name: ("output", getattr(self, name), {"units": "1", "long_name": what[name]}) for name in what
                  if getattr(self, name) is not None}
        ds = self._dataset(
            {"coefficients": (("output", "term"), self.coefficients,
                              {UNITS_VARIABLE: "output_unit", "long_name": "PCE coefficients (orthonormal basis of the "
                                                                           "input marginals)"}),
             "multi_index": (("term", "param"), self.indices, {"units": "1", "long_name": "polynomial degree of "
                                                                                         "each parameter in the term"}),
             "output_variance": ("output", self.output_variance,
                                 {UNITS_VARIABLE: "output_unit_squared",
                                  "long_name": "population variance of training y"}),
             **errors},
            coords={"term": ("term", np.arange(self.indices.shape[0]), {"units": "1", "long_name": "basis term"})},
            attrs={**self.info, "loo_mean": float(np.mean(self.loo)),
                   "modified_loo_mean": float(np.mean(self.modified_loo)),
                   "empirical_mean": float(np.mean(self.empirical))},
        )
        return ds

    @classmethod
    def from_dataset(cls, ds: xr.Dataset) -> PCE:
        info = {k: ds.attrs[k] for k in ("degree", "q", "solver", "n_train")}
        # stores written before the degree cap was recorded (pce stage version 1) have no cap attrs, before the
        # cross-validation option (version 6) no cv_folds: they reported the corrected LOO
        info.update({k: ds.attrs[k] for k in ("degree_cap", "degree_cap_warning", "cv_folds") if k in ds.attrs})
        return cls(**cls._common(ds), **cls._stored_inputs(ds), indices=ds["multi_index"].values,
                   coefficients=ds["coefficients"].values, loo=ds["loo"].values, modified_loo=ds["modified_loo"].values,
                   empirical=ds["empirical"].values, output_variance=ds["output_variance"].values, info=info,
                   cv_error=ds["cv_error"].values if "cv_error" in ds else None)
