"""Declared schemas for the xarray Datasets that flow between stages.

A schema lists the dimensions a Dataset must have and, per variable, its dimensions, dtype kind and unit
(``attrs["units"]``, or units per element along a dimension: :mod:`spflow.core.cf_metadata`). The executor
validates every stage input before ``run`` and every output before it is stored; a violation raises :class:`~spflow.core.errors.SchemaError` naming the stage, the port, the variable and what
was expected versus found.

We keep this small module instead of ``pandera.xarray``: our contract needs only dims, dtype kinds and units, and we
want every message to carry the stage and port.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
import xarray as xr

from .cf_metadata import UNITS_VARIABLE, has_units_per_element, udunits
from .errors import SchemaError
from .netcdf_layout import DatasetLayout

__all__ = ["Variable", "DatasetSchema", "ANY"]

#: Placeholder for "any Dataset" (used by generic stages such as data loaders).
ANY = None

_KIND_NAMES = {"f": "float", "i": "integer", "u": "unsigned integer", "b": "bool", "U": "string", "O": "object"}


@dataclass(frozen=True)
class Variable:
    """One variable of a Dataset schema.

    ``dims`` is the exact tuple of dimension names (``None`` = any). ``kind`` is a numpy dtype-kind string
    (``"f"`` float, ``"i"`` integer, ``"fi"`` either, ``"U"`` string …). ``units`` is the required
    ``attrs["units"]`` (``None`` = not checked; ``""`` = must be present, any value). ``required=False`` makes the
    variable optional, but when present it must match. Float variables must be finite unless ``allow_nan``.
    ``units_variable`` declares units that differ along a dimension (:mod:`spflow.core.cf_metadata`): the variable
    has no ``units`` attribute but ``attrs["units_variable"]`` naming that string variable, which must exist along
    one or more of the variable's dims (a covariance's units variable runs along both of its dims). ``long_name`` is
    the CF ``long_name`` the variable is written with (:meth:`DatasetSchema.annotate`).
    """

    dims: tuple[str, ...] | None
    kind: str = "f"
    units: str | None = None
    required: bool = True
    allow_nan: bool = False
    doc: str = ""
    long_name: str = ""
    units_variable: str | None = None


@dataclass(frozen=True)
class DatasetSchema:
    """Schema of a Dataset: required dims, variables (data variables or coordinates) and required attrs."""

    dims: tuple[str, ...] = ()
    variables: dict[str, Variable] = field(default_factory=dict)
    attrs: tuple[str, ...] = ()
    doc: str = ""

    def validate(self, ds: Any, *, stage: str, port: str, values: bool = True) -> None:
        """Raise :class:`SchemaError` if ``ds`` does not match; ``values=False`` checks the structure only (dims,
        variables, dtypes, units, attrs) without reading the arrays (the finiteness check). ``ds`` is an
        ``xarray.Dataset`` or, with ``values=False``, the :class:`~spflow.core.netcdf_layout.DatasetLayout` of a
        stored one (a cache entry, read from its header)."""
        where = f"stage {stage!r} port {port!r}"
        if isinstance(ds, DatasetLayout) and values:
            raise ValueError(f"{where}: a DatasetLayout holds no values; validate it with values=False")
        if not isinstance(ds, (xr.Dataset, DatasetLayout)):
            raise SchemaError(f"{where}: expected an xarray.Dataset, found {type(ds).__name__}")
        missing_dims = [d for d in self.dims if d not in ds.dims]
        if missing_dims:
            raise SchemaError(f"{where}: expected dims {list(self.dims)}, found {list(ds.dims)} (missing {missing_dims})")
        for name in self.attrs:
            if name not in ds.attrs:
                raise SchemaError(f"{where}: expected Dataset attribute {name!r}, found attrs {sorted(ds.attrs)}")
        for name, spec in self.variables.items():
            if name not in ds.variables:
                if spec.required:
                    raise SchemaError(
                        f"{where} variable {name!r}: expected a variable with dims {spec.dims}, "
                        f"found none (variables: {sorted(map(str, ds.variables))})"
                    )
                continue
            var = ds.variables[name]
            if spec.dims is not None and tuple(var.dims) != tuple(spec.dims):
                raise SchemaError(f"{where} variable {name!r}: expected dims {spec.dims}, found {tuple(var.dims)}")
            if var.dtype.kind not in spec.kind:
                expected = " or ".join(_KIND_NAMES.get(k, k) for k in spec.kind)
                raise SchemaError(f"{where} variable {name!r}: expected dtype {expected}, found {var.dtype}")
            if spec.units is not None:
                found = var.attrs.get("units")
                if found is None:
                    raise SchemaError(f"{where} variable {name!r}: expected attrs['units'] = {spec.units!r}, found no units")
                # (a unit declared in the catalogue notation and stored in its UDUNITS form, as the executor
                # writes every result -- cf_metadata.note_units -- is the same unit: "PV" and "1", "cP" and "cpoise")
                if spec.units and udunits(found) != udunits(spec.units):
                    raise SchemaError(f"{where} variable {name!r}: expected units {spec.units!r}, found {found!r}")
            if spec.units_variable is not None:
                self._check_units_variable(ds, name, spec.units_variable, where)
            if values and var.dtype.kind == "f" and not spec.allow_nan and not np.isfinite(var.values).all():
                raise SchemaError(f"{where} variable {name!r}: expected finite values, found NaN or inf")

    @staticmethod
    def _check_units_variable(ds: xr.Dataset | DatasetLayout, name: str, expected: str, where: str) -> None:
        found = ds.variables[name].attrs.get(UNITS_VARIABLE)
        if found != expected:
            raise SchemaError(f"{where} variable {name!r}: expected attrs[{UNITS_VARIABLE!r}] = {expected!r} (units "
                              f"per element), found {found!r}")
        if not has_units_per_element(ds, name):
            units = ds.variables.get(expected)
            raise SchemaError(f"{where} variable {name!r}: units per element need no attrs['units'] (found "
                              f"{ds.variables[name].attrs.get('units')!r}) and {expected!r} a string variable along "
                              f"some of its dims {tuple(ds.variables[name].dims)} (found "
                              f"{None if units is None else (units.dims, str(units.dtype))})")

    def annotate(self, ds: xr.Dataset) -> xr.Dataset:
        """A shallow copy of ``ds`` with each declared variable's ``long_name`` and ``units_variable`` written into its
        attrs where it has none (the executor annotates every output before validating and storing it)."""
        ds = ds.copy(deep=False)
        for name, spec in self.variables.items():
            if name in ds.variables:
                attrs = ds.variables[name].attrs
                if spec.long_name:
                    attrs.setdefault("long_name", spec.long_name)
                if spec.units_variable is not None:
                    attrs.setdefault(UNITS_VARIABLE, spec.units_variable)
        return ds

    def describe(self) -> str:
        """One line per variable, for ``spflow list``."""
        lines = [f"dims {list(self.dims)}"] if self.dims else []
        for name, spec in self.variables.items():
            unit = f" [{spec.units}]" if spec.units else f" [units in {spec.units_variable}]" if spec.units_variable \
                else ""
            opt = "" if spec.required else " (optional)"
            lines.append(f"{name}{tuple(spec.dims) if spec.dims is not None else ''}{unit}{opt}")
        return "; ".join(lines)
