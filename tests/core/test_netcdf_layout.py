"""A stored Dataset's layout read from the netCDF header is what ``xarray.open_dataset`` presents (the reference,
opened in each test), and the schema check on a cache entry rejects on it what it rejects on the Dataset."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

from spflow import DatasetSchema, SchemaError, Variable
from spflow.core.netcdf_layout import DatasetLayout, read_layout


def _stored(ds: xr.Dataset, path) -> object:
    """Write ``ds`` as the store does (no encoding, netCDF4)."""
    ds.drop_encoding().to_netcdf(path, engine="netcdf4")
    return path


def _assert_same_attrs(found: dict, expected: dict) -> None:
    assert sorted(found) == sorted(expected)
    for key, value in expected.items():
        np.testing.assert_array_equal(found[key], value, err_msg=key)


def everything_the_store_writes() -> xr.Dataset:
    n = 3
    data = {f"{kind}{bits}": ("sample", np.arange(n, dtype=f"{kind}{bits // 8}"), {"units": "1"})
            for kind in "iu" for bits in (8, 16, 32, 64)}
    data.update(
        f32=("sample", np.array([0.5, np.nan, 1.5], dtype="f4"), {"units": "Pa"}),
        f64=(("sample", "param"), np.ones((n, 2)), {"units_variable": "unit", "long_name": "x"}),
        flag=("sample", np.array([True, False, True])),
        label=("sample", np.array(["a", "bb", "ccc"], dtype=object)),
        time_like=("sample", np.arange(3.0), {"units": "s"}),  # an abbreviation: a plain float for xarray
    )
    return xr.Dataset(data, coords={"param": ["CRK", "AD41"], "unit": ("param", ["1", "m2"]),
                                    "pv": ("sample", [0.1, 0.2, 0.3], {"units": "1"})},
                      attrs={"title": "t", "count": 3, "ratio": 0.5, "levels": np.array([1, 2])})


def test_the_header_layout_is_what_xarray_opens(tmp_path):
    path = _stored(everything_the_store_writes(), tmp_path / "data.nc")
    layout = read_layout(path)
    assert layout is not None
    with xr.open_dataset(path, engine="netcdf4") as ref:
        assert dict(layout.dims) == dict(ref.sizes)
        _assert_same_attrs(dict(layout.attrs), dict(ref.attrs))
        assert sorted(layout.variables) == sorted(map(str, ref.variables))
        for name, var in ref.variables.items():
            found = layout.variables[name]
            assert found.dims == var.dims, name
            assert found.ndim == var.ndim, name
            assert found.dtype.kind == var.dtype.kind, name
            if var.dtype.kind != "U":  # (the header does not give the longest string's length)
                assert found.dtype == var.dtype, name
            _assert_same_attrs(dict(found.attrs), dict(var.attrs))


@pytest.mark.parametrize("what, ds", [
    ("times", xr.Dataset({"t": ("x", np.array(["2020-01-01", "2020-01-02"], dtype="datetime64[ns]"))})),
    ("time deltas", xr.Dataset({"t": ("x", np.array([1, 2], dtype="timedelta64[s]"))})),
    ("a time unit xarray may decode", xr.Dataset({"t": ("x", np.array([1, 2]), {"units": "hours"})})),
    ("byte strings (a character array)", xr.Dataset({"s": ("x", np.array([b"a", b"bc"]))})),
    ("a masked integer", xr.Dataset({"i": ("x", np.array([1, 2]), {"_FillValue": -1})})),
    ("a packed variable", xr.Dataset({"v": ("x", np.array([1.0, 2.0]), {"scale_factor": 0.5})})),
])
def test_an_encoding_the_header_does_not_reproduce_is_left_to_xarray(tmp_path, what, ds):
    assert read_layout(_stored(ds, tmp_path / "data.nc")) is None, what


def test_the_layout_of_an_xarray_dataset_holds_its_decoded_structure(tmp_path):
    path = _stored(xr.Dataset({"t": ("x", np.array(["2020-01-01", "2020-01-02"], dtype="datetime64[ns]")),
                               "s": ("x", np.array([b"a", b"bc"]))}, attrs={"a": "b"}), tmp_path / "data.nc")
    with xr.open_dataset(path, engine="netcdf4") as ds:
        layout = DatasetLayout.of(ds)
    assert dict(layout.dims) == {"x": 2} and dict(layout.attrs) == {"a": "b"}
    assert layout.variables["t"].dtype.kind == "M" and layout.variables["t"].dims == ("x",)
    assert layout.variables["s"].dtype == np.dtype("S2") and layout.variables["s"].dims == ("x",)  # chars joined


SCHEMA = DatasetSchema(dims=("sample", "param"), variables={
    "dp": Variable(("sample", "pv"), units="Pa"),
    "flag": Variable(("sample",), kind="b"),
    "name": Variable(("sample",), kind="U"),
    "values": Variable(("sample", "param"), units_variable="unit"),
})


def _good() -> xr.Dataset:
    return xr.Dataset({"dp": (("sample", "pv"), np.ones((2, 3)), {"units": "Pa"}),
                       "flag": ("sample", [True, False]), "name": ("sample", ["a", "b"]),
                       "values": (("sample", "param"), np.ones((2, 2)), {"units_variable": "unit"})},
                      coords={"param": ["CRK", "AD41"], "unit": ("param", ["1", "m2"])})


@pytest.mark.parametrize("mutate, message", [
    (lambda ds: ds, None),
    (lambda ds: ds.rename({"sample": "s"}), "expected dims ['sample', 'param']"),
    (lambda ds: ds.assign(dp=ds.dp.T), "variable 'dp': expected dims ('sample', 'pv'), found ('pv', 'sample')"),
    (lambda ds: ds.assign(dp=ds.dp.assign_attrs(units="kPa")), "variable 'dp': expected units 'Pa', found 'kPa'"),
    (lambda ds: ds.assign(dp=ds.dp.astype(int)), "variable 'dp': expected dtype float, found int64"),
    (lambda ds: ds.assign(flag=ds.flag.astype("i1")), "variable 'flag': expected dtype bool, found int8"),
    (lambda ds: ds.assign(name=("sample", [1.0, 2.0])), "variable 'name': expected dtype string, found float64"),
    (lambda ds: ds.drop_vars("unit"), "variable 'values': units per element need no attrs['units']"),
    (lambda ds: ds.rename({"dp": "z"}), "variable 'dp': expected a variable with dims"),
])
def test_the_stored_layout_is_rejected_exactly_when_the_dataset_is(tmp_path, mutate, message):
    ds = mutate(_good())
    layout = read_layout(_stored(ds, tmp_path / "data.nc"))
    assert layout is not None
    if message is None:
        SCHEMA.validate(ds, stage="s", port="output")
        SCHEMA.validate(layout, stage="s", port="output", values=False)
        return
    for checked in (ds, layout):
        with pytest.raises(SchemaError) as info:
            SCHEMA.validate(checked, stage="s", port="output", values=False)
        assert message in str(info.value)


def test_a_layout_cannot_be_checked_for_values(tmp_path):
    layout = read_layout(_stored(_good(), tmp_path / "data.nc"))
    with pytest.raises(ValueError, match="a DatasetLayout holds no values; validate it with values=False"):
        SCHEMA.validate(layout, stage="s", port="output")
