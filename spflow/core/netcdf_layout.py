"""The layout of a stored netCDF Dataset (dims, variables, dtypes, attributes) read from the file's header alone.

What :meth:`spflow.core.schema.DatasetSchema.validate` checks on a cache entry (``values=False``) is structure only:
dimension names and sizes, each variable's dims, dtype kind and attributes, the Dataset's attributes. Opening the
file with xarray for that decodes every variable (CF conventions) and, for any string variable, makes xarray import
dask when it is installed (0.3-0.5 s per process, most of ``spflow status`` on a cached pipeline, issue #23).

:func:`read_layout` reads the same structure with netCDF4 directly, as xarray would decode it, for the encodings the
store writes (``xarray.Dataset.to_netcdf`` of a Dataset without encoding): floats (their ``_FillValue`` is encoding,
not an attribute), integers, booleans (``int8`` with ``dtype = "bool"``), variable-length strings, the
``coordinates`` attribute (encoding). A file using any other CF encoding (packed or masked integers, times, time
units, character arrays, enums, groups ...) is not guessed at: :func:`read_layout` returns ``None`` and the caller
opens it with xarray (:meth:`DatasetLayout.of`), which decodes it exactly. Tests compare both against
``xarray.open_dataset``.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["VariableLayout", "DatasetLayout", "read_layout"]

#: Attributes xarray's decoding moves into ``encoding`` for the encodings :func:`read_layout` reproduces.
_ENCODING_ATTRS = ("_FillValue", "coordinates")
#: Attributes that make xarray change a variable's dtype or values on decoding (read_layout leaves such files to it).
_DECODED_ATTRS = ("scale_factor", "add_offset", "_Unsigned", "missing_value", "calendar", "_Encoding", "dtype",
                  "flag_values", "valid_range", "valid_min", "valid_max")
#: Units xarray (depending on its version and options) decodes as times or time deltas.
_TIME_UNITS = ("days", "hours", "minutes", "seconds", "milliseconds", "microseconds", "nanoseconds")


@dataclass(frozen=True)
class VariableLayout:
    """One variable's dims, dtype and attributes, without its values."""

    dims: tuple[str, ...]
    dtype: np.dtype
    attrs: Mapping[str, Any]

    @property
    def ndim(self) -> int:
        return len(self.dims)


@dataclass(frozen=True)
class DatasetLayout:
    """A Dataset's structure as ``xarray.open_dataset`` would present it: ``dims`` (name -> size), ``variables``
    (data variables and coordinates) and ``attrs``; no values."""

    dims: Mapping[str, int]
    variables: Mapping[str, VariableLayout]
    attrs: Mapping[str, Any]

    @classmethod
    def of(cls, ds: Any) -> DatasetLayout:
        """The layout of an ``xarray.Dataset``."""
        return cls(dict(ds.sizes), {str(name): VariableLayout(tuple(map(str, var.dims)), var.dtype, dict(var.attrs))
                                    for name, var in ds.variables.items()}, dict(ds.attrs))


def read_layout(path: str | Path) -> DatasetLayout | None:
    """The layout of the netCDF file ``path`` read from its header, or ``None`` if it uses an encoding this reader
    does not reproduce exactly (open it with xarray then). Raises ``OSError`` if the file cannot be read."""
    import netCDF4  # noqa: PLC0415  (the backend xarray would load anyway; imported on first read)

    with netCDF4.Dataset(path, "r") as nc:
        if nc.groups or "coordinates" in nc.ncattrs():
            return None
        variables = {}
        for name, var in nc.variables.items():
            decoded = _decoded(var)
            if decoded is None:
                return None
            variables[name] = decoded
        dims = {d: len(nc.dimensions[d]) for v in variables.values() for d in v.dims}
        return DatasetLayout(dims, variables, {key: nc.getncattr(key) for key in nc.ncattrs()})


def _decoded(var: Any) -> VariableLayout | None:
    """``var`` (a netCDF4 variable) as xarray decodes it, or ``None`` if that takes more than the rules below."""
    attrs = {key: var.getncattr(key) for key in var.ncattrs()}
    if var.dtype is str:  # variable-length strings: xarray decodes them to a numpy unicode array
        dtype = np.dtype(str)
    elif isinstance(var.datatype, np.dtype) and var.datatype.kind in "fiu":
        dtype = var.datatype  # (a compound, enum or vlen datatype is not a numpy dtype: not read here)
    else:
        return None
    if dtype.kind == "i" and dtype.itemsize == 1 and attrs.get("dtype") == "bool":
        dtype = np.dtype(bool)
        del attrs["dtype"]
    units = attrs.get("units")
    if (any(key in attrs for key in _DECODED_ATTRS) or ("_FillValue" in attrs and dtype.kind != "f")
            or (isinstance(units, str) and (" since " in units or units.strip() in _TIME_UNITS))):
        return None
    for key in _ENCODING_ATTRS:
        attrs.pop(key, None)
    return VariableLayout(tuple(var.dimensions), dtype, attrs)
