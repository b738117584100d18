"""Canonical content hashing of parameters and xarray/numpy data.

``joblib.hash`` of an xarray object depends on ``.encoding`` (including the source file path) and on lazily opened
backends, so identical data can hash differently (docs/architecture.md, Pieces: hashing). Here every object is reduced
to a canonical
byte stream: for a Dataset, each variable (data variables and coordinates, sorted by name) contributes its name, dims,
dtype, shape, canonical attrs and raw C-order bytes; Dataset attrs are included; ``.encoding`` never is. Lazy variables
are materialised through ``.values``, so the content — not the object — is hashed.

The dispatcher is a :func:`functools.singledispatch`; plugins add types through the ``spflow_register_hashers`` hook.
"""

from __future__ import annotations

import hashlib
import json
import math
from collections.abc import Mapping
from functools import singledispatch
from typing import Any, Callable

import numpy as np
import xarray as xr

__all__ = ["canonical_hash", "register_hasher", "update_hash", "canonical_json"]

_CHUNK = 1 << 24  # feed large arrays to the hasher in 16 MiB pieces to bound temporary memory


def _tag(h: "hashlib._Hash", tag: str) -> None:
    data = tag.encode()
    h.update(len(data).to_bytes(8, "little"))
    h.update(data)


@singledispatch
def update_hash(obj: Any, h: "hashlib._Hash") -> None:
    """Feed the canonical form of ``obj`` into the hash object ``h``."""
    raise TypeError(
        f"spflow cannot hash objects of type {type(obj).__name__}; register a hasher with the "
        "spflow_register_hashers hook or pass JSON-compatible values"
    )


@update_hash.register(type(None))
def _(obj: None, h) -> None:
    _tag(h, "none")


@update_hash.register(bool)
def _(obj: bool, h) -> None:
    _tag(h, f"bool:{obj}")


@update_hash.register(int)
def _(obj: int, h) -> None:
    _tag(h, f"int:{obj}")


@update_hash.register(float)
def _(obj: float, h) -> None:
    if obj.is_integer() and math.isfinite(obj):
        _tag(h, f"int:{int(obj)}")  # 2.0 and 2 are the same parameter value
    else:
        _tag(h, f"float:{obj!r}")


@update_hash.register(str)
def _(obj: str, h) -> None:
    _tag(h, f"str:{obj}")


@update_hash.register(bytes)
def _(obj: bytes, h) -> None:
    _tag(h, "bytes")
    h.update(len(obj).to_bytes(8, "little"))
    h.update(obj)


@update_hash.register(list)
@update_hash.register(tuple)
def _(obj, h) -> None:
    _tag(h, f"seq:{len(obj)}")
    for item in obj:
        update_hash(item, h)


@update_hash.register(Mapping)
def _(obj: Mapping, h) -> None:
    _tag(h, f"map:{len(obj)}")
    for key in sorted(obj, key=str):
        _tag(h, str(key))
        update_hash(obj[key], h)


@update_hash.register(np.generic)
def _(obj: np.generic, h) -> None:
    update_hash(obj.item(), h)


@update_hash.register(np.ndarray)
def _(obj: np.ndarray, h) -> None:
    arr = np.asarray(obj)
    if arr.dtype.kind == "O":
        _tag(h, f"objarray:{arr.shape}")
        for item in arr.ravel().tolist():
            update_hash(item, h)
        return
    arr = np.ascontiguousarray(arr)
    _tag(h, f"array:{arr.dtype.str}:{arr.shape}")
    flat = arr.reshape(-1).view(np.uint8)
    for start in range(0, flat.size, _CHUNK):
        h.update(flat[start : start + _CHUNK])


def _update_variable(name: str, var: xr.Variable, h) -> None:
    _tag(h, f"var:{name}:{','.join(map(str, var.dims))}")
    update_hash(dict(var.attrs), h)
    update_hash(np.asarray(var.values), h)


@update_hash.register(xr.Dataset)
def _(obj: xr.Dataset, h) -> None:
    _tag(h, "dataset")
    coord_names = set(map(str, obj.coords))
    for name in sorted(map(str, obj.variables)):
        _tag(h, "coord" if name in coord_names else "data")
        _update_variable(name, obj.variables[name], h)
    update_hash(dict(obj.attrs), h)


@update_hash.register(xr.DataArray)
def _(obj: xr.DataArray, h) -> None:
    _tag(h, f"dataarray:{obj.name}")
    update_hash(obj.to_dataset(name="__data__") if obj.name is None else obj.to_dataset(), h)


def register_hasher(kind: type, func: Callable[[Any, Any], None]) -> None:
    """Register ``func(obj, h)`` as the canonical hasher for ``kind`` (it calls ``update_hash`` on its parts)."""
    update_hash.register(kind)(func)


def canonical_hash(obj: Any) -> str:
    """Hex SHA-256 of the canonical form of ``obj``."""
    h = hashlib.sha256()
    update_hash(obj, h)
    return h.hexdigest()


def canonical_json(obj: Any) -> str:
    """Deterministic JSON text of a JSON-compatible value (sorted keys), used in metadata records."""
    return json.dumps(obj, sort_keys=True, separators=(",", ":"), default=str)
