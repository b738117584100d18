"""The store: atomic writes (a crash leaves no partial entry), every version kept, checksums enforced."""

import numpy as np
import pytest
import xarray as xr

from spflow import SchemaError
from spflow.core.cache import CorruptEntryError, Store


def _ds(v=1.0):
    return xr.Dataset({"y": ("x", np.full(4, v), {"units": "m"})}, attrs={"note": "test"})


def test_roundtrip_and_metadata(tmp_path):
    store = Store(tmp_path)
    store.save("ab" * 32, _ds(), {"stage": "s"}, where="test")
    assert store.has("ab" * 32) and store.verify("ab" * 32)
    xr.testing.assert_identical(store.load("ab" * 32), _ds())
    record = store.record("ab" * 32)
    assert record["stage"] == "s" and len(record["sha256"]) == 64 and record["nbytes"] > 0


def test_crash_during_write_leaves_no_entry_and_no_temp(tmp_path, monkeypatch):
    store = Store(tmp_path)

    def explode(self, *args, **kwargs):
        raise OSError("disk full")

    monkeypatch.setattr(xr.Dataset, "to_netcdf", explode)
    with pytest.raises(OSError, match="disk full"):
        store.save("cd" * 32, _ds(), {}, where="test")
    assert not store.has("cd" * 32)
    assert list((tmp_path / "tmp").iterdir()) == []


def test_corrupt_entry_is_refused(tmp_path):
    store = Store(tmp_path)
    store.save("ef" * 32, _ds(), {}, where="test")
    path = store._entry("ef" * 32) / "data.nc"
    raw = bytearray(path.read_bytes())
    raw[-20] ^= 0xFF
    path.write_bytes(bytes(raw))
    assert not store.verify("ef" * 32)
    with pytest.raises(CorruptEntryError):
        store.load("ef" * 32)


def test_all_versions_kept_and_clean(tmp_path):
    store = Store(tmp_path)
    for i in range(3):
        store.save(f"{i:02d}" * 32, _ds(i), {}, where="test")
    assert all(store.verify(f"{i:02d}" * 32) for i in range(3))
    assert store.clean() == 3
    assert not store.has("00" * 32)


def test_unserialisable_attrs_are_named(tmp_path):
    ds = _ds()
    ds.attrs["flag"] = True
    with pytest.raises(SchemaError, match="stage 'x' output attribute 'flag' = True cannot be stored"):
        Store(tmp_path).save("01" * 32, ds, {}, where="stage 'x' output")
