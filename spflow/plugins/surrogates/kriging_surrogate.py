"""Kriging surrogates behind the surrogate contract: the common part of PC-Kriging (kind ``pck``) and the plain GP
(kind ``gp``), thesis §3.8, Eqs. 3.18-3.21.

Output columns are split into *groups* that share one correlation kernel (one set of length scales, one Cholesky
factor); every column keeps its own trend, GLS coefficients and process variance (:mod:`.kriging`).

* ``share="output"`` (default): one group per column -- UQLab's treatment of vector outputs (one Kriging model per
  output component), which the thesis used. On BCF1 (9 parameters, N = 200, dp and recovery at 44 PV steps each) it
  was 2-6x more accurate on an independent LHS set than sharing.
* ``share="variable"``: one group per (variable, experiment): the 44 time steps of a QoI share their length scales
  (fitted on the sum of their likelihoods). Prediction is ~20x cheaper (one triangular product per QoI and batch
  instead of one per column) -- the option for calibrations that call the proxy point by point 10^5 times.

Measured numbers: ``benchmarks/bench_kriging.py`` and ``docs/surrogates.md``.

Storage (no pickle): training inputs (physical units) and outputs, the trend multi-indices, each column's trend mask,
GLS coefficients and process variance, the group of each column, each group's length scales and nugget, the
kernel name and the Kriging LOO errors. :meth:`from_dataset` recomputes the Cholesky factors and GLS quantities from
the training data and hyperparameters with the same code as the fit, so in one process it predicts exactly as the
fitted object did. (Across processes BLAS may round differently; with a near-singular correlation matrix -- long
length scales, condition number up to n/nugget ~ 10^10 -- the recomputed β̂ then differs from the stored one in the
6th-7th digit, so the stored coefficients are a record, not a checksum.)
"""

from __future__ import annotations

from typing import ClassVar

import numpy as np
import xarray as xr

from spflow.core.cf_metadata import UNITS_VARIABLE
from spflow.core.errors import ParameterError, SchemaError

from .blas import single_threaded_blas
from .contract import Surrogate, input_box, reference_points, resolve_inputs
from .input_marginals import Marginal, check_support
from .kriging import KERNELS, UniversalKriging
from .outputs import OutputIndex
from .pck_modes import MODES, fit_group

__all__ = ["KrigingSurrogate", "SHARING", "RESTARTS", "NUGGET", "output_groups"]

SHARING = ("output", "variable")
#: Default number of L-BFGS-B starts of the length-scale fit (Eq. 3.21), shared by ``GP.fit``, ``PCK.fit``, their
#: stages and :mod:`spflow.surrogates`.
RESTARTS = 3
#: Default nugget τ on the diagonal of the unit-variance correlation matrix (``R = C(θ) + τI``), shared likewise. It
#: regularises like a noise variance of τσ², so it caps the accuracy of an interpolating fit: 1e-8 left spflow's GP
#: 8x less accurate than scikit-learn's (alpha 1e-10 on a normalised y) on Ishigami at N = 400, 1e-12 leaves 1.3x,
#: with no loss on the BCF1 simulator. Not lower: R's condition number reaches ~N/τ (issue #24; docs/surrogates.md,
#: "Kriging peers").
NUGGET = 1e-12


def output_groups(outputs: OutputIndex, share: str) -> np.ndarray:
    """Group number of every output column for the sharing rule ``share`` (see the module docstring).

    ``share="variable"`` on several outputs that each carry their own (variable, experiment) label would give one
    group per output, i.e. ``share="output"`` under another name; that is refused rather than done silently.
    """
    if share not in SHARING:
        raise ParameterError(f"Kriging hyperparameter sharing {share!r} is not known; allowed: {list(SHARING)}")
    if share == "output":
        return np.arange(len(outputs))
    keys = [f"{v}\x00{e}" for v, e in zip(outputs.variable, outputs.experiment)]
    group = np.unique(keys, return_inverse=True)[1].ravel()
    if len(outputs) > 1 and group.max() + 1 == len(outputs):
        labels = sorted({(str(v), str(e)) for v, e in zip(outputs.variable, outputs.experiment)})
        shown = ", ".join(f"{v}/{e}" if e else v for v, e in labels[:4]) + (", ..." if len(labels) > 4 else "")
        raise ParameterError(f"Kriging share='variable' shares length scales between the outputs of one (variable, "
                             f"experiment), but each of the {len(outputs)} outputs has its own label ({shown}), so "
                             f"nothing would be shared: use share='output' (one model per output), or give the "
                             f"outputs that should share length scales the same variable label")
    return group


class KrigingSurrogate(Surrogate):
    """Universal Kriging of every output column with a (possibly constant-only) polynomial trend, on the reference
    variables of the inputs (:meth:`to_unit`: [-1, 1]^d for uniform inputs).

    Subclasses set :attr:`kind` and build the trend candidates; construction from stored arrays is common.
    """

    #: Long name of the kind (error messages).
    label: ClassVar[str] = "Kriging"

    def __init__(self, names: list[str], lower: np.ndarray, upper: np.ndarray, outputs: OutputIndex,
                 x: np.ndarray, y: np.ndarray, indices: np.ndarray, trend: np.ndarray, group: np.ndarray,
                 lengthscale: np.ndarray, nugget: np.ndarray, kernel: str, info: dict, inputs=None,
                 input_note: str = ""):
        from .basis import design_matrix  # numba: on first use

        marginals, x, y = self.check_training(names, lower, upper, outputs, x, y, inputs)
        super().__init__(names, lower, upper, outputs, marginals, input_note)
        self.x, self.y = x, y
        self.indices = np.ascontiguousarray(indices, dtype=np.int64)
        self.trend = np.asarray(trend, dtype=bool)
        self.group = np.asarray(group, dtype=np.int64)
        self.lengthscale = np.atleast_2d(np.asarray(lengthscale, dtype=float))
        self.nugget = np.atleast_1d(np.asarray(nugget, dtype=float))
        self.kernel = str(kernel)
        self.info = dict(info)
        self._check_shapes()
        z = self.to_unit(self.x)
        basis = design_matrix(z, self.indices, self.families)
        self.coefficients = np.zeros((len(outputs), self.indices.shape[0]))
        self.process_variance = np.zeros(len(outputs))
        self.loo = np.zeros(len(outputs))
        self._models = []
        for g in range(self.lengthscale.shape[0]):
            cols = np.flatnonzero(self.group == g)
            used = self.trend[cols].any(axis=0)
            model = UniversalKriging(z, self.y[:, cols], basis[:, used], self.trend[np.ix_(cols, used)], self.kernel,
                                     self.lengthscale[g], self.nugget[g])
            self.coefficients[np.ix_(cols, used)] = model.coefficients.T
            self.process_variance[cols] = model.process_variance
            self.loo[cols] = model.relative_loo()
            self._models.append((cols, used, model))

    def _check_shapes(self) -> None:
        """The stored hyperparameters and trends fit the training data (checked by :meth:`check_training`)."""
        d, m = len(self.names), len(self.outputs)
        what = f"{self.label} surrogate"
        if self.indices.ndim != 2 or self.indices.shape[1] != d:
            raise ParameterError(f"{what}: multi-indices must be (term, {d}), got {self.indices.shape}")
        if self.trend.shape != (m, self.indices.shape[0]):
            raise ParameterError(f"{what}: trend mask must be (output, term) = ({m}, {self.indices.shape[0]}), got "
                                 f"{self.trend.shape}")
        n_groups = self.lengthscale.shape[0]
        if self.group.shape != (m,) or set(self.group.tolist()) != set(range(n_groups)):
            raise ParameterError(f"{what}: output groups must number the {n_groups} length-scale rows 0..{n_groups - 1}"
                                 f" and cover all {m} outputs")
        if self.lengthscale.shape != (n_groups, d) or self.nugget.shape != (n_groups,):
            raise ParameterError(f"{what}: length scales must be (group, {d}) and nuggets (group,), got "
                                 f"{self.lengthscale.shape} and {self.nugget.shape}")
        if not (self.nugget >= 0).all():
            raise ParameterError(f"{what}: nuggets must be >= 0, got {self.nugget}")
        if self.kernel not in KERNELS:
            raise ParameterError(f"{what}: kernel {self.kernel!r} is not known; allowed: {sorted(KERNELS)}")

    # -- fitting ----------------------------------------------------------------------------------------------------
    @classmethod
    def check_options(cls, *, mode: str, kernel: str, share: str, nugget: float, restarts: int) -> None:
        """Raise :class:`ParameterError` naming the first bad fitting option (before any work)."""
        if mode not in MODES:
            raise ParameterError(f"{cls.label}: mode {mode!r} is not known; allowed: {list(MODES)}")
        if kernel not in KERNELS:
            raise ParameterError(f"{cls.label}: kernel {kernel!r} is not known; allowed: {sorted(KERNELS)}")
        if share not in SHARING:
            raise ParameterError(f"{cls.label}: share {share!r} is not known; allowed: {list(SHARING)}")
        if isinstance(restarts, bool) or not (isinstance(restarts, (int, np.integer)) and restarts >= 1):
            raise ParameterError(f"{cls.label}: restarts must be an integer >= 1, got {restarts!r}")
        if not (isinstance(nugget, (int, float)) and np.isfinite(nugget) and 0 <= nugget <= 0.1):
            raise ParameterError(f"{cls.label}: nugget must be a number in [0, 0.1], got {nugget!r}")

    @classmethod
    def check_training(cls, names: list[str], lower: np.ndarray, upper: np.ndarray, outputs: OutputIndex,
                       x: np.ndarray, y: np.ndarray, inputs=None) -> tuple[list[Marginal], np.ndarray, np.ndarray]:
        """The inputs' marginals (:func:`.contract.resolve_inputs`: ``inputs``, or uniform on the box), ``x`` (n, d)
        and ``y`` (n, m) as float arrays; shapes, finiteness and the box (the supports of the marginals) checked."""
        x = np.atleast_2d(np.asarray(x, dtype=float))
        y = np.asarray(y, dtype=float)
        y = y[:, None] if y.ndim == 1 else y
        d, m = len(names), len(outputs)
        if x.ndim != 2 or x.shape[1] != d or y.shape != (x.shape[0], m):
            raise ParameterError(f"{cls.label}: need x (n, {d}) and y (n, {m}) for parameters {list(names)} and "
                                 f"{m} outputs; got x {x.shape}, y {y.shape}")
        if x.shape[0] < 3:
            raise ParameterError(f"{cls.label}: need at least 3 training points, got {x.shape[0]}")
        if not (np.isfinite(x).all() and np.isfinite(y).all()):
            raise ParameterError(f"{cls.label}: training x and y must be finite")
        marginals = resolve_inputs(names, lower, upper, inputs, cls.label)
        if inputs is not None:
            check_support(marginals, names, x, f"{cls.label}: training points")
            return marginals, x, y
        lower, upper = input_box(marginals)
        slack = 1e-9 * (upper - lower)
        if ((x < lower - slack) | (x > upper + slack)).any():
            raise ParameterError(f"{cls.label}: training points must lie in the box lower={lower}, upper={upper}")
        return marginals, x, y

    @classmethod
    def fit_trends(cls, names: list[str], lower: np.ndarray, upper: np.ndarray, outputs: OutputIndex,
                   x: np.ndarray, y: np.ndarray, indices: np.ndarray, orders: list[np.ndarray], *, mode: str,
                   kernel: str, share: str, nugget: float, restarts: int, seed: int, parallel=None,
                   info: dict | None = None, progress=None, inputs=None) -> KrigingSurrogate:
        """Fit length scales (and, in ``optimal`` mode, trend sizes) group by group and build the surrogate.

        ``indices`` (P, d) are the trend candidates; ``orders[j]`` ranks column j's candidates (rows of ``indices``).
        ``parallel`` (a :class:`joblib.Parallel`) spreads the groups over workers; ``progress`` (e.g.
        ``ctx.progress``) wraps the iterable of groups to report how many were fitted (dispatched, in parallel).
        ``inputs`` (one marginal per parameter, :mod:`.input_marginals`; None = uniform on the box): the kernel and
        the trend act on the reference variables ξ = T(x) of the marginals, so the length scales are in ξ.
        """
        from .basis import design_matrix

        cls.check_options(mode=mode, kernel=kernel, share=share, nugget=nugget, restarts=restarts)
        marginals, x, y = cls.check_training(names, lower, upper, outputs, x, y, inputs)
        if len(orders) != y.shape[1]:
            raise ParameterError(f"{cls.label}: need one trend order per output ({y.shape[1]}), got {len(orders)}")
        group = output_groups(outputs, share)
        z = reference_points(marginals, x)
        basis = design_matrix(z, indices, [m.polynomials for m in marginals])
        seeds = np.random.SeedSequence(seed).generate_state(group.max() + 1)
        jobs = []
        for g in range(group.max() + 1):
            cols = np.flatnonzero(group == g)
            used = np.unique(np.concatenate([orders[j] for j in cols]))
            local = [np.searchsorted(used, orders[j]) for j in cols]
            jobs.append((cols, used, (z, y[:, cols], basis[:, used], local, mode, kernel, nugget, restarts,
                                      int(seeds[g]))))
        groups = jobs if progress is None else progress(jobs)
        if parallel is None:
            results = [fit_group(*args) for _, _, args in groups]
        else:
            from joblib import delayed

            results = parallel(delayed(fit_group)(*args) for _, _, args in groups)
        trend = np.zeros((y.shape[1], indices.shape[0]), dtype=bool)
        lengthscale = np.empty((len(jobs), len(names)))
        for g, ((cols, used, _), (mask, lengths)) in enumerate(zip(jobs, results)):
            trend[np.ix_(cols, used)] = mask
            lengthscale[g] = lengths
        info = {"mode": mode, "share": share, "restarts": restarts, "seed": seed, **(info or {})}
        return cls(names, lower, upper, outputs, x, y, indices, trend, group, lengthscale,
                   np.full(len(jobs), float(nugget)), kernel, info, marginals)

    # -- prediction -------------------------------------------------------------------------------------------------
    def _predict(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return self._evaluate(x, variance=True)

    def _predict_mean(self, x: np.ndarray) -> np.ndarray:
        return self._evaluate(x, variance=False)[0]

    def _evaluate(self, x: np.ndarray, variance: bool) -> tuple[np.ndarray, np.ndarray | None]:
        """Mean and (if ``variance``) variance of every output at validated points ``x``."""
        from .basis import design_matrix

        z = self.to_unit(x)
        basis = design_matrix(z, self.indices, self.families)
        mean = np.empty((z.shape[0], len(self.outputs)))
        var = np.empty_like(mean) if variance else None
        with single_threaded_blas():  # many small products: one limit around all the groups
            for cols, used, model in self._models:
                mean[:, cols], group_var = model.predict(z, basis[:, used], variance)
                if variance:
                    var[:, cols] = group_var
        return mean, var

    # -- storage ----------------------------------------------------------------------------------------------------
    def to_dataset(self) -> xr.Dataset:
        return self._dataset(
            {"train_x": (("train", "param"), self.x, {"long_name": "training points"}),
             "train_y": (("train", "output"), self.y, {UNITS_VARIABLE: "output_unit",
                                                       "long_name": "training responses"}),
             "multi_index": (("term", "param"), self.indices, {"units": "1", "long_name": "polynomial degree of each "
                                                                                         "parameter in the term"}),
             "trend": (("output", "term"), self.trend.astype(np.int8),
                       {"units": "1", "long_name": "1 if the term is in the output's Kriging trend"}),
             "coefficients": (("output", "term"), self.coefficients,
                              {UNITS_VARIABLE: "output_unit", "long_name": "GLS trend coefficients"}),
             "process_variance": ("output", self.process_variance,
                                  {UNITS_VARIABLE: "output_unit_squared", "long_name": "Kriging process variance σ²"}),
             "output_group": ("output", self.group, {"units": "1", "long_name": "length-scale group of the output"}),
             "lengthscale": (("group", "param"), self.lengthscale,
                             {"units": "1", "long_name": "correlation length ℓ in the reference space of the inputs "
                                                        "([-1, 1] for uniform ones); Eq. 3.20's θ = sqrt(2) ℓ for "
                                                        "the gaussian kernel"}),
             "nugget": ("group", self.nugget, {"units": "1", "long_name": "added to the correlation diagonal"}),
             "loo": ("output", self.loo, {"units": "1", "long_name": "Kriging LOO error ε_LOO (Eq. 3.8, Dubrule)"})},
            coords={"term": ("term", np.arange(self.indices.shape[0]), {"units": "1", "long_name": "trend term"}),
                    "train": ("train", np.arange(self.x.shape[0]), {"units": "1", "long_name": "training point"}),
                    "group": ("group", np.arange(self.lengthscale.shape[0]),
                              {"units": "1", "long_name": "length-scale group"})},
            attrs={"kernel": self.kernel, "loo_mean": float(np.mean(self.loo)), **self.info},
        )

    @classmethod
    def from_dataset(cls, ds: xr.Dataset) -> KrigingSurrogate:
        needed = ("train_x", "train_y", "multi_index", "trend", "coefficients", "output_group", "lengthscale", "nugget")
        missing = [v for v in needed if v not in ds.variables]
        if missing or "kernel" not in ds.attrs:
            raise SchemaError(f"{cls.label} surrogate Dataset lacks {missing or ['attrs.kernel']}")
        info = {k: ds.attrs[k] for k in ds.attrs
                if k not in ("surrogate", "kernel", "loo_mean") and not k.startswith("units_")}
        return cls(**cls._common(ds), **cls._stored_inputs(ds),
                   x=ds["train_x"].transpose("train", "param").values,
                   y=ds["train_y"].transpose("train", "output").values, indices=ds["multi_index"].values,
                   trend=ds["trend"].values.astype(bool), group=ds["output_group"].values,
                   lengthscale=ds["lengthscale"].values, nugget=ds["nugget"].values, kernel=ds.attrs["kernel"],
                   info=info)
