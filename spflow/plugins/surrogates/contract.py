"""The one surrogate contract: every proxy (PCE, PC-Kriging, plain GP, third-party ones) predicts a mean and a
variance for a batch of parameter vectors and round-trips through an xarray Dataset without pickle.

A surrogate Dataset has dims ``param`` (with ``lower``/``upper`` bounds of the uniform input box) and ``output``
(labelled by :class:`~.outputs.OutputIndex`), ``attrs["surrogate"]`` naming its kind, and whatever arrays the kind
needs (coefficients with their multi-indices, hyperparameters, training data, errors). Stages downstream
(calibration, design) call :func:`load_surrogate` and never care which kind they got, so a pipeline swaps the
surrogate by naming another stage for the surrogate node.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from typing import ClassVar

import numpy as np
import xarray as xr

from spflow.core.errors import ParameterError
from spflow.core.cf_metadata import UNITS_VARIABLE
from spflow.core.plugins import get_registry
from spflow.core.schema import DatasetSchema, Variable

from .outputs import OutputIndex

__all__ = ["Surrogate", "SURROGATE", "STORED_SURROGATE", "load_surrogate", "surrogate_kinds", "with_parameter_units"]

#: Variables of a stored surrogate that hold parameter values (units per parameter).
PARAMETER_VALUED = ("lower", "upper", "train_x")

#: Schema of every stored surrogate.
SURROGATE = DatasetSchema(
    dims=("param", "output"),
    variables={
        "lower": Variable(("param",), units=None, long_name="lower end of the training box"),
        "upper": Variable(("param",), units=None, long_name="upper end of the training box"),
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
        "lower": Variable(("param",), units_variable="param_unit", long_name="lower end of the training box"),
        "upper": Variable(("param",), units_variable="param_unit", long_name="upper end of the training box"),
        "param_unit": Variable(("param",), kind="U", long_name="UDUNITS unit of each input parameter")},
    attrs=SURROGATE.attrs,
    doc="a fitted surrogate with the units of its inputs (see attrs['surrogate'] for its kind)",
)

class Surrogate(ABC):
    """A fitted proxy of a vector-valued model on a uniform box ``lower <= x <= upper`` (physical units)."""

    #: The name stored in ``attrs["surrogate"]``; unique per kind.
    kind: ClassVar[str] = ""

    def __init__(self, names: list[str], lower: np.ndarray, upper: np.ndarray, outputs: OutputIndex):
        self.names = [str(n) for n in names]
        self.lower = np.asarray(lower, dtype=float)
        self.upper = np.asarray(upper, dtype=float)
        self.outputs = outputs

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
        return x

    def to_unit(self, x: np.ndarray) -> np.ndarray:
        """Affine map of the box onto [-1, 1]^d (the auxiliary space of the Legendre basis)."""
        return 2.0 * (x - self.lower) / (self.upper - self.lower) - 1.0

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
            {"lower": ("param", self.lower, {"long_name": "lower end of the training box"}),
             "upper": ("param", self.upper, {"long_name": "upper end of the training box"}), **variables},
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
