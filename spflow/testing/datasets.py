"""Dataset helpers of the conformance checks: an exact comparison that says what differs, the cache's netCDF round
trip, and NaN poisoning of an input."""

from __future__ import annotations

import hashlib
import tempfile
import warnings

import numpy as np
import xarray as xr

from spflow.core.cache import Store

__all__ = ["differences", "cache_round_trip", "with_nan", "float_data_variables"]

#: Differences listed before "... and N more".
_SHOWN = 3


def _same_values(a: xr.Variable, b: xr.Variable) -> bool:
    if a.shape != b.shape:
        return False
    if a.dtype.kind in "fc" and b.dtype.kind in "fc":
        return bool(np.array_equal(a.values, b.values, equal_nan=True))
    return bool(np.array_equal(np.asarray(a.values, dtype=object), np.asarray(b.values, dtype=object)))


def _same_attrs(a: dict, b: dict) -> bool:
    if set(a) != set(b):
        return False
    return all(np.array_equal(np.asarray(a[k], dtype=object), np.asarray(b[k], dtype=object)) for k in a)


def differences(a: xr.Dataset, b: xr.Dataset) -> list[str]:
    """What differs between ``a`` and ``b`` (variables, coordinates, dims, dtype kinds, values bit for bit with NaN
    equal to NaN, attributes); empty when they are identical."""
    found = []
    if set(a.variables) != set(b.variables):
        only_a, only_b = sorted(map(str, set(a.variables) - set(b.variables))), sorted(map(str, set(b.variables) -
                                                                                              set(a.variables)))
        found.append(f"variables only in the first: {only_a}, only in the second: {only_b}")
    for name in sorted(map(str, set(a.variables) & set(b.variables))):
        va, vb = a.variables[name], b.variables[name]
        if va.dims != vb.dims:
            found.append(f"variable {name!r}: dims {va.dims} vs {vb.dims}")
        elif va.dtype.kind != vb.dtype.kind and not {va.dtype.kind, vb.dtype.kind} <= {"U", "O", "S"}:
            found.append(f"variable {name!r}: dtype {va.dtype} vs {vb.dtype}")
        elif not _same_values(va, vb):
            if va.dtype.kind in "fc" and va.shape == vb.shape:
                diff = np.abs(np.asarray(va.values, float) - np.asarray(vb.values, float))
                where = np.isnan(va.values) != np.isnan(vb.values)
                found.append(f"variable {name!r}: values differ (max |difference| {np.nanmax(diff, initial=0.0):.3g}, "
                             f"NaN at different places in {int(where.sum())} of {va.size})")
            else:
                found.append(f"variable {name!r}: values differ")
        if not _same_attrs(va.attrs, vb.attrs):
            found.append(f"variable {name!r}: attrs {dict(va.attrs)} vs {dict(vb.attrs)}")
    if not _same_attrs(a.attrs, b.attrs):
        keys = sorted(k for k in set(a.attrs) | set(b.attrs)
                      if k not in a.attrs or k not in b.attrs
                      or not np.array_equal(np.asarray(a.attrs[k], dtype=object), np.asarray(b.attrs[k], dtype=object)))
        found.append("Dataset attrs differ: " + ", ".join(f"{k}: {a.attrs.get(k, '<absent>')!r} vs "
                                                           f"{b.attrs.get(k, '<absent>')!r}" for k in keys))
    if len(found) > _SHOWN:
        found = found[:_SHOWN] + [f"... and {len(found) - _SHOWN} more"]
    return found


def cache_round_trip(ds: xr.Dataset, where: str) -> xr.Dataset:
    """``ds`` written and read back by the cache (:class:`spflow.core.cache.Store`) in a temporary directory, as a
    node's result is stored and reused."""
    key = hashlib.sha256(b"spflow.testing").hexdigest()
    with tempfile.TemporaryDirectory(prefix="spflow-testing-") as root, warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        store = Store(root)
        store.save(key, ds, {"stage": where}, where=where)
        return store.load(key)


def float_data_variables(ds: xr.Dataset) -> list[str]:
    """Names of the non-empty float data variables (not coordinates) of ``ds``."""
    return [str(n) for n, v in ds.data_vars.items() if v.dtype.kind == "f" and v.size]


def with_nan(ds: xr.Dataset, names: list[str]) -> xr.Dataset:
    """A deep copy of ``ds`` with one finite value of each variable in ``names`` (its middle finite element) set to
    NaN."""
    out = ds.copy(deep=True)
    for name in names:
        values = np.array(out[name].values, dtype=float)
        finite = np.flatnonzero(np.isfinite(values))
        if finite.size:
            values.flat[finite[finite.size // 2]] = np.nan
            out[name] = out[name].copy(data=values)
    return out
