"""The one surrogate contract: every proxy (PCE, PC-Kriging, plain GP, third-party ones) predicts a mean and a
variance for a batch of parameter vectors and round-trips through an xarray Dataset without pickle.

A surrogate Dataset has dims ``param`` (with ``lower``/``upper``, the support of each input, and ``distribution`` /
``distribution_parameters``, its marginal law, :mod:`.input_marginals`) and ``output`` (labelled by
:class:`~.outputs.OutputIndex`), ``attrs["surrogate"]`` naming its kind, and whatever arrays the kind needs
(coefficients with their multi-indices, hyperparameters, training data, errors). The inputs are uniform on
[lower, upper] unless given other marginals; a Dataset stored before the marginals were recorded (no
``distribution``) loads as uniform on its box, and the loaded surrogate says so in :attr:`Surrogate.input_note`.
Stages downstream (calibration, design) call :func:`load_surrogate` and never care which kind they got, so a
pipeline swaps the surrogate by naming another stage for the surrogate node.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import replace
from typing import ClassVar

import numpy as np
import xarray as xr

from spflow.core.errors import ParameterError
from spflow.core.cf_metadata import UNITS_VARIABLE
from spflow.core.plugins import get_registry
from spflow.core.schema import DatasetSchema, Variable

from .input_marginals import (MARGINAL_SCHEMA, Marginal, Uniform, check_support, marginal_variables,
                              marginals_from_dataset)
from .orthonormal_polynomials import PolynomialFamily
from .outputs import OutputIndex

__all__ = ["Surrogate", "SURROGATE", "STORED_SURROGATE", "load_surrogate", "surrogate_kinds", "with_parameter_units",
           "input_box", "reference_points", "resolve_inputs", "UNIFORM_ASSUMED"]

#: Variables of a stored surrogate that hold parameter values (units per parameter).
PARAMETER_VALUED = ("lower", "upper", "train_x")

#: Schema of every stored surrogate.
SURROGATE = DatasetSchema(
    dims=("param", "output"),
    variables={
        # ±inf where a marginal is unbounded (normal, lognormal); a NaN is refused by the kinds' constructors
        "lower": Variable(("param",), units=None, allow_nan=True, long_name="lower end of the input's support"),
        "upper": Variable(("param",), units=None, allow_nan=True, long_name="upper end of the input's support"),
        **MARGINAL_SCHEMA,
        "output_variable": Variable(("output",), kind="U", long_name="variable of each output column"),
        "output_pv": Variable(("output",), units="1", allow_nan=True,
                              long_name="injected pore volumes of each output column"),
    },
    attrs=("surrogate",),
    doc="a fitted surrogate (see attrs['surrogate'] for its kind)",
)

#: A surrogate as a stage stores it and as the stages reading one from a pipeline take it: :data:`SURROGATE` with the
#: box in the units of the parameter space, units per element ``param_unit`` (:func:`with_parameter_units`). One
#: built in memory (``Surrogate.to_dataset()``, what :func:`load_surrogate` takes) need not carry them.
STORED_SURROGATE = DatasetSchema(
    dims=SURROGATE.dims,
    variables=SURROGATE.variables | {
        **{k: replace(SURROGATE.variables[k], units_variable="param_unit") for k in ("lower", "upper")},
        "param_unit": Variable(("param",), kind="U", long_name="UDUNITS unit of each input parameter")},
    attrs=SURROGATE.attrs,
    doc="a fitted surrogate with the units of its inputs (see attrs['surrogate'] for its kind)",
)

#: What a surrogate loaded from a Dataset without recorded marginals assumes (:attr:`Surrogate.input_note`).
UNIFORM_ASSUMED = ("the stored surrogate records no input distribution (written before they were recorded): its "
                   "inputs are taken as uniform on [lower, upper]")


def input_box(inputs) -> tuple[np.ndarray, np.ndarray]:
    """(lower, upper) arrays of the supports of the marginals ``inputs`` (±inf where unbounded)."""
    return (np.array([m.support[0] for m in inputs], dtype=float),
            np.array([m.support[1] for m in inputs], dtype=float))


class Surrogate(ABC):
    """A fitted proxy of a vector-valued model of independent inputs (physical units): uniform on the box
    ``lower <= x <= upper``, or with the marginals ``inputs`` (:mod:`.input_marginals`), whose supports must then be
    the box (:func:`input_box`)."""

    #: The name stored in ``attrs["surrogate"]``; unique per kind.
    kind: ClassVar[str] = ""

    def __init__(self, names: list[str], lower: np.ndarray, upper: np.ndarray, outputs: OutputIndex,
                 inputs: list[Marginal] | None = None, input_note: str = ""):
        self.names = [str(n) for n in names]
        self.lower = np.asarray(lower, dtype=float)
        self.upper = np.asarray(upper, dtype=float)
        self.outputs = outputs
        #: What was assumed about the inputs when the surrogate was built ("" when nothing was).
        self.input_note = str(input_note)
        #: One marginal per parameter (:mod:`.input_marginals`).
        self.inputs = resolve_inputs(self.names, self.lower, self.upper, inputs, type(self).__name__)

    @property
    def families(self) -> list[PolynomialFamily]:
        """The orthonormal polynomial family of each input's reference variable."""
        return [m.polynomials for m in self.inputs]

    @property
    def uniform(self) -> bool:
        """True when every input is uniform (the reference space is [-1, 1]^d with Legendre polynomials)."""
        return all(isinstance(m, Uniform) for m in self.inputs)

    # -- prediction -----------------------------------------------------------------------------------------------
    def predict(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Mean and variance, each (n, n_output), at ``x`` (n, n_param) in physical units."""
        return self._predict(self.check_points(x))

    @abstractmethod
    def _predict(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Kind-specific prediction on validated points."""

    def predict_mean(self, x: np.ndarray) -> np.ndarray:
        """Mean only, (n, n_output), at ``x`` (n, n_param) in physical units: for kinds whose variance costs more than
        their mean (Kriging: an (N, n) triangular product per length-scale group) the variance is not computed."""
        return self._predict_mean(self.check_points(x))

    def _predict_mean(self, x: np.ndarray) -> np.ndarray:
        """Kind-specific mean on validated points; a kind with a cheaper mean than :meth:`_predict` overrides it."""
        return self._predict(x)[0]

    def check_points(self, x: np.ndarray) -> np.ndarray:
        """``x`` as a float (n, n_param) array; a wrong width or a non-finite value raises before any work."""
        x = np.atleast_2d(np.asarray(x, dtype=float))
        if x.ndim != 2 or x.shape[1] != len(self.names):
            raise ParameterError(f"surrogate input: expected points of shape (n, {len(self.names)}) for parameters "
                                 f"{self.names}, got {x.shape}")
        if not np.isfinite(x).all():
            raise ParameterError("surrogate input: points must be finite")
        if not self.uniform:  # a uniform box extrapolates as before; the other maps are undefined or clip outside
            check_support(self.inputs, self.names, x, "surrogate input")
        return x

    def to_unit(self, x: np.ndarray) -> np.ndarray:
        """The isoprobabilistic map of physical points ``x`` (n, d) onto the reference variables of the polynomial
        families (:mod:`.input_marginals`): for uniform inputs the affine map of the box onto [-1, 1]^d."""
        return reference_points(self.inputs, x)

    def predict_dataset(self, x: np.ndarray) -> xr.Dataset:
        """Predictions as a Dataset with dims (``sample``, ``output``) and the output labels as coordinates."""
        x = self.check_points(x)
        mean, var = self._predict(x)
        ds = xr.Dataset({"mean": (("sample", "output"), mean, {UNITS_VARIABLE: "output_unit",
                                                               "long_name": "surrogate mean"}),
                         "variance": (("sample", "output"), var, {UNITS_VARIABLE: "output_unit_squared",
                                                                  "long_name": "surrogate error variance"})},
                        coords={"sample": ("sample", np.arange(x.shape[0]), {"units": "1", "long_name": "point"}),
                                **self.outputs.coords()})
        ds.attrs = self.outputs.unit_attrs()
        return ds

    # -- storage --------------------------------------------------------------------------------------------------
    @abstractmethod
    def to_dataset(self) -> xr.Dataset:
        """The surrogate as a Dataset (use :meth:`_dataset` for the common part)."""

    @classmethod
    @abstractmethod
    def from_dataset(cls, ds: xr.Dataset) -> Surrogate:
        """Rebuild from :meth:`to_dataset`'s output."""

    def _dataset(self, variables: dict, coords: dict | None = None, attrs: dict | None = None) -> xr.Dataset:
        ds = xr.Dataset(
            {"lower": ("param", self.lower, {"long_name": SURROGATE.variables["lower"].long_name}),
             "upper": ("param", self.upper, {"long_name": SURROGATE.variables["upper"].long_name}),
             **marginal_variables(self.inputs), **variables},
            coords={"param": ("param", self.names, {"long_name": "input parameter (design column)"}),
                    **self.outputs.coords(), **(coords or {})},
        )
        ds.attrs = {"surrogate": self.kind, **self.outputs.unit_attrs(), **(attrs or {})}
        return ds

    @staticmethod
    def _common(ds: xr.Dataset) -> dict:
        """Constructor arguments shared by every kind, read back from a stored Dataset."""
        return {"names": [str(n) for n in ds["param"].values], "lower": ds["lower"].values,
                "upper": ds["upper"].values, "outputs": OutputIndex.from_dataset(ds)}

    @staticmethod
    def _stored_inputs(ds: xr.Dataset) -> dict:
        """The ``inputs`` (marginals) and ``input_note`` constructor arguments read back from a stored Dataset: a
        Dataset without ``distribution`` (stored before the marginals were recorded, or by a kind that keeps none) is
        uniform on its box, which ``input_note`` says."""
        inputs = marginals_from_dataset(ds, "stored surrogate")
        return {"inputs": inputs, "input_note": UNIFORM_ASSUMED if inputs is None else ""}


def resolve_inputs(names: list[str], lower: np.ndarray, upper: np.ndarray, inputs, what: str) -> list[Marginal]:
    """The marginals of a surrogate's inputs: ``inputs`` (one :class:`~.input_marginals.Marginal` per name, whose
    supports must be ``lower``/``upper``), or, when None, uniform on the box [lower, upper]. ``what`` names the kind in
    the errors."""
    lower, upper = np.asarray(lower, dtype=float), np.asarray(upper, dtype=float)
    if inputs is None:
        if lower.shape != (len(names),) or upper.shape != lower.shape \
                or not np.all(np.isfinite(lower) & np.isfinite(upper) & (lower < upper)):
            raise ParameterError(f"{what}: bounds must satisfy lower < upper (finite) for each of the {len(names)} "
                                 f"parameters {list(names)}")
        return [Uniform(lo, hi) for lo, hi in zip(lower, upper)]
    inputs = list(inputs)
    if len(inputs) != len(names) or not all(isinstance(m, Marginal) for m in inputs):
        raise ParameterError(f"{what}: inputs must be one marginal distribution (spflow.surrogates.Uniform, Normal, "
                             f"LogNormal, TruncatedNormal, Beta) per parameter {list(names)}, got {inputs!r}")
    support_lower, support_upper = input_box(inputs)
    if not (np.array_equal(support_lower, lower) and np.array_equal(support_upper, upper)):
        raise ParameterError(f"{what}: lower/upper {lower}/{upper} are not the supports {support_lower}/"
                             f"{support_upper} of the inputs {inputs}")
    return inputs


def reference_points(inputs, x: np.ndarray) -> np.ndarray:
    """Points ``x`` (n, d) in physical units mapped column by column onto the reference variables of ``inputs``."""
    x = np.atleast_2d(np.asarray(x, dtype=float))
    z = np.empty_like(x)
    for j, marginal in enumerate(inputs):
        z[:, j] = marginal.to_reference(x[:, j])
    return z


def with_parameter_units(ds: xr.Dataset, space: xr.Dataset) -> xr.Dataset:
    """A stored surrogate ``ds`` with the units of its inputs: the ``space``'s ``unit`` of each parameter as
    ``param_unit``, and every variable along ``param`` that holds parameter values (the box, Kriging's training
    points) in units per element (:mod:`spflow.core.cf_metadata`). A surrogate stage calls it on what it returns."""
    names = [str(n) for n in ds["param"].values]
    ds = ds.assign(param_unit=("param", space["unit"].sel(param=names).values.astype(str),
                               {"long_name": "UDUNITS unit of each input parameter"}))
    for name in PARAMETER_VALUED:
        if name in ds:
            ds[name].attrs[UNITS_VARIABLE] = "param_unit"
    return ds


def surrogate_kinds() -> list[str]:
    """Names of the loadable surrogate kinds (built-in and from plugins)."""
    return sorted(get_registry().surrogate_kinds)


def load_surrogate(ds: xr.Dataset) -> Surrogate:
    """Rebuild whichever surrogate ``ds`` holds: ``attrs["surrogate"]`` names the kind, a kind registered through
    the plugin hook ``spflow_register_surrogate_kinds`` (the built-ins: ``pce``, ``gp``, ``pck``)."""
    SURROGATE.validate(ds, stage="load_surrogate", port="surrogate")
    return get_registry().surrogate_kind(ds.attrs["surrogate"]).from_dataset(ds)
