"""Canonical hashing: content decides, encoding/paths/lazy opening/attr order do not."""

import hashlib

import numpy as np
import xarray as xr

from spflow.core.hashing import canonical_hash, register_hasher, update_hash


def _ds(values=(1.0, 2.0, 3.0)):
    return xr.Dataset(
        {"dp": ("pv", np.array(values), {"units": "Pa", "long_name": "pressure drop"})},
        coords={"pv": [0.0, 0.1, 0.2]},
        attrs={"experiment": "BCF1", "cells": 100},
    )


def test_same_bytes_at_two_paths_and_lazy_opens_hash_equal(tmp_path):
    ds = _ds()
    a, b = tmp_path / "a.nc", tmp_path / "sub_b.nc"
    ds.to_netcdf(a)
    ds.to_netcdf(b)
    with xr.open_dataset(a) as lazy_a, xr.open_dataset(b) as lazy_b, xr.open_dataset(a) as lazy_a2:
        assert lazy_a["dp"].encoding["source"] != lazy_b["dp"].encoding["source"]
        assert canonical_hash(lazy_a) == canonical_hash(lazy_b) == canonical_hash(lazy_a2) == canonical_hash(ds)


def test_attr_order_is_irrelevant_but_content_dtype_dims_attrs_matter():
    base = canonical_hash(_ds())
    reordered = _ds()
    reordered.attrs = {"cells": 100, "experiment": "BCF1"}
    assert canonical_hash(reordered) == base
    assert canonical_hash(_ds((1.0, 2.0, 3.0000001))) != base
    as_f32 = _ds()
    as_f32["dp"] = as_f32["dp"].astype("float32")
    assert canonical_hash(as_f32) != base
    renamed = _ds().rename({"dp": "dq"})
    assert canonical_hash(renamed) != base
    units = _ds()
    units["dp"].attrs["units"] = "bar"
    assert canonical_hash(units) != base
    as_coord = _ds().set_coords("dp")
    assert canonical_hash(as_coord) != base


def test_array_hash_covers_exactly_the_raw_bytes_once():
    arr = np.arange(10.0)
    h = hashlib.sha256()
    update_hash(arr, h)
    header = f"array:{arr.dtype.str}:{arr.shape}".encode()
    ref = hashlib.sha256(len(header).to_bytes(8, "little") + header + arr.tobytes()).hexdigest()
    assert h.hexdigest() == ref
    assert canonical_hash(np.asfortranarray(np.ones((3, 4)))) == canonical_hash(np.ones((3, 4)))


def test_params_hash_canonically():
    assert canonical_hash({"a": 1, "b": [1, 2]}) == canonical_hash({"b": [1, 2], "a": 1})
    assert canonical_hash({"a": 2.0}) == canonical_hash({"a": 2})
    assert canonical_hash({"a": 2.5}) != canonical_hash({"a": 2})
    assert canonical_hash(np.float64(0.1)) == canonical_hash(0.1)
    assert canonical_hash("1") != canonical_hash(1)


def test_registered_hasher_extends_the_dispatch():
    class Point:
        def __init__(self, x):
            self.x = x

    register_hasher(Point, lambda obj, h: update_hash(("Point", obj.x), h))
    assert canonical_hash(Point(1.0)) == canonical_hash(Point(1.0)) != canonical_hash(Point(2.0))
