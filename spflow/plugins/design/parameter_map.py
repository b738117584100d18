"""Design columns -> forward-model parameters (:class:`ParameterMap`): the one place where a point of a parameter
space becomes the simulator's parameters.

A parameter space's columns (coordinate ``param``) are the labels of its calibrated parameters
(:mod:`.calibrated_parameter`). The ``parameter_space`` stage records, per label, the UTCHEM names it sets
(variable ``utchem_names``: the names separated by spaces) and its scale (variable ``scale``): ``linear``, the column
holds the value in the forward model's units; ``log``, the column holds log10 of the value (units
``lg(re 1 <unit>)``), so that a uniform design, prior or search box in the column is log-uniform in the value. Every
Dataset derived from a space -- designs, the NSGA-II calibration, the MCMC posterior -- carries both variables
(:meth:`ParameterMap.attach`), and every stage that simulates a design (``forward`` and the stages that run it:
``adaptive_pce``, ``sobol_screening``, ``nsga2_calibration``'s held-out check, ``posterior_predictive``,
``slug_design``) turns a row into parameters with :meth:`ParameterMap.forward_params`.

A Dataset without these variables (a design written by hand, a space built from plain UTCHEM names by an older
version) has UTCHEM names as columns: each label sets the parameter of its name, on a linear scale.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
import xarray as xr

from spflow.core.cf_metadata import UNITS_VARIABLE
from spflow.core.errors import ParameterError

from .calibrated_parameter import CalibratedParameter

__all__ = ["NAMES_VAR", "SCALE_VAR", "ParameterMap", "log_unit"]

#: variables that record the map on a Dataset with a ``param`` coordinate
NAMES_VAR, SCALE_VAR = "utchem_names", "scale"


def log_unit(unit: str) -> str:
    """UDUNITS unit of log10 of a value in ``unit`` (``"-"`` or ``""``: dimensionless): ``lg(re 1 mD)``."""
    return "lg(re 1)" if unit in ("", "-", "1") else f"lg(re 1 {unit})"


@dataclass(frozen=True)
class ParameterMap:
    """Per design column (``labels``): the UTCHEM ``names`` it sets and whether it holds log10 of the value."""

    labels: tuple[str, ...]
    names: tuple[tuple[str, ...], ...]
    log: tuple[bool, ...]

    @classmethod
    def of_parameters(cls, parameters: Sequence[CalibratedParameter]) -> ParameterMap:
        """The map of validated calibrated parameters (one column each, in order)."""
        return cls(tuple(p.label for p in parameters), tuple(p.names for p in parameters),
                   tuple(p.log for p in parameters))

    @classmethod
    def identity(cls, labels: Sequence[str]) -> ParameterMap:
        """Columns that are UTCHEM names, each setting its own parameter on a linear scale."""
        labels = tuple(str(n) for n in labels)
        return cls(labels, tuple((label,) for label in labels), (False,) * len(labels))

    @classmethod
    def of(cls, ds: xr.Dataset) -> ParameterMap:
        """The map recorded on ``ds`` (a space, design, calibration or posterior; module docstring); the identity
        map when ``ds`` records none."""
        labels = tuple(str(n) for n in ds["param"].values)
        if NAMES_VAR not in ds:
            return cls.identity(labels)
        names = tuple(tuple(str(v).split()) for v in ds[NAMES_VAR].values)
        scales = [str(v) for v in ds[SCALE_VAR].values] if SCALE_VAR in ds else ["linear"] * len(labels)
        bad = sorted({s for s in scales if s not in ("linear", "log")})
        if bad or any(not n for n in names):
            raise ParameterError(f"parameter map of columns {list(labels)}: every column needs UTCHEM names "
                                 f"(variable {NAMES_VAR!r}) and a scale 'linear' or 'log' (variable {SCALE_VAR!r}); "
                                 f"got names {[list(n) for n in names]}, scales {scales}")
        return cls(labels, names, tuple(s == "log" for s in scales))

    def variables(self) -> dict:
        """The map as Dataset variables on dim ``param``."""
        return {NAMES_VAR: ("param", np.array([" ".join(n) for n in self.names]),
                            {"long_name": "forward-model (UTCHEM) parameters each column sets"}),
                SCALE_VAR: ("param", np.array(["log" if g else "linear" for g in self.log]),
                            {"long_name": "linear: the column is the value; log: the column is log10 of the value"})}

    def attach(self, ds: xr.Dataset) -> xr.Dataset:
        """``ds`` (with this map's ``param`` coordinate) carrying the map."""
        have = [str(n) for n in ds["param"].values]
        if have != list(self.labels):
            raise ParameterError(f"parameter map of columns {list(self.labels)} does not fit a Dataset with columns "
                                 f"{have}")
        return ds.assign(self.variables())

    def design(self, values, attrs: Mapping | None = None, units: Sequence[str] | None = None,
               **coords) -> xr.Dataset:
        """A ``design`` Dataset (dims ``sample``, ``param``) of the rows ``values`` carrying this map; ``units``: the
        UDUNITS unit of each column (a space's ``unit``), recorded as ``unit`` with ``values`` in units per element
        (:mod:`spflow.core.cf_metadata`) — without it ``values`` has no units; ``coords``: extra coordinates (e.g.
        ``generation=("sample", ...)``)."""
        values = np.atleast_2d(np.asarray(values, dtype=float))
        ds = xr.Dataset({"values": (("sample", "param"), values, {"long_name": "design points"})},
                        coords={"sample": ("sample", np.arange(values.shape[0]), {"units": "1",
                                                                                "long_name": "sample number"}),
                                "param": ("param", list(self.labels), {"long_name": "design column"}), **coords},
                        attrs=dict(attrs or {}))
        if units is not None:
            if len(units) != len(self.labels):
                raise ParameterError(f"design: {len(units)} units for the columns {list(self.labels)}")
            ds["unit"] = ("param", np.asarray([str(u) for u in units]), {"long_name": "UDUNITS unit of each column"})
            ds["values"].attrs[UNITS_VARIABLE] = "unit"
        return ds.assign(self.variables())

    def forward_params(self, row) -> dict[str, float]:
        """UTCHEM name -> value of one design row (the column's value, or 10**column on a log scale, for every name
        the column sets)."""
        row = np.asarray(row, dtype=float).ravel()
        if row.size != len(self.labels):
            raise ParameterError(f"a design row needs {len(self.labels)} values (columns {list(self.labels)}), got "
                                 f"{row.size}")
        out: dict[str, float] = {}
        for names, log, x in zip(self.names, self.log, row):
            value = float(10.0 ** x) if log else float(x)
            for name in names:
                out[name] = value
        return out

    def columns(self, params: Mapping[str, float]) -> np.ndarray:
        """The design row of UTCHEM values ``params`` (inverse of :meth:`forward_params`); every name a column sets
        must be given with one value."""
        row = []
        for label, names, log in zip(self.labels, self.names, self.log):
            missing = [n for n in names if n not in params]
            if missing:
                raise ParameterError(f"column {label!r} sets {list(names)}; no value given for {missing}")
            values = {float(params[n]) for n in names}
            if len(values) > 1:
                raise ParameterError(f"column {label!r} sets {list(names)} to one value; given {sorted(values)}")
            value = values.pop()
            row.append(np.log10(value) if log else value)
        return np.array(row)
