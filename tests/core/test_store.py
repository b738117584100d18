"""The store: atomic writes (a crash leaves no partial entry), every version kept, checksums enforced."""

import errno
import os

import numpy as np
import pytest
import xarray as xr

from spflow import SchemaError
from spflow.core.cache import MARKER, CorruptEntryError, Store
from spflow.core.errors import CacheError


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
    store.save("ab" * 32, _ds(), {}, where="test")

    def explode(self, path, *args, **kwargs):
        open(path, "wb").write(b"CDF partial")  # a half-written file, then the disk is full
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), str(path))

    monkeypatch.setattr(xr.Dataset, "to_netcdf", explode)
    with pytest.raises(CacheError) as info:
        store.save("cd" * 32, _ds(), {}, where="node 'n' (stage 's') output")
    message = str(info.value)
    assert "\n" not in message
    assert message.startswith(f"node 'n' (stage 's') output: cannot store the result in cache {tmp_path}: ")
    assert "No space left on device" in message
    assert not store.has("cd" * 32) and not (tmp_path / "objects" / "cd").exists()
    assert list((tmp_path / "tmp").iterdir()) == []
    assert store.verify("ab" * 32)  # the finished entry is kept


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


def _tree(root):
    return sorted(str(p.relative_to(root)) for p in root.rglob("*"))


def test_clean_refuses_a_directory_that_is_not_a_cache(tmp_path, capsys):
    from spflow.cli import main

    home = tmp_path / "documents"
    (home / "objects" / "ab").mkdir(parents=True)  # store-like names, but not a store
    (home / "objects" / "ab" / "photo.jpg").write_bytes(b"\xff\xd8")
    (home / "tmp").mkdir()
    (home / "tmp" / "draft.txt").write_text("draft")
    (home / "thesis.tex").write_text("\\chapter{}")
    before = _tree(home)
    for tmp_only in (False, True):
        with pytest.raises(CacheError, match=f"{home} is not a spflow cache .*refusing to delete anything in it"):
            Store(home).clean(tmp_only=tmp_only)
    assert main(["clean", "--cache", str(home)]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"spflow: error: {home} is not a spflow cache") and err.count("\n") == 1
    with pytest.raises(CacheError, match=r"is not a spflow cache .* holds \['objects', 'tmp'\]; refusing to write"):
        Store(home).save("ab" * 32, _ds(), {}, where="test")
    assert _tree(home) == before


def test_clean_deletes_only_what_the_store_manages(tmp_path, capsys):
    from spflow.cli import main

    root = tmp_path / "cache"
    store = Store(root)
    for i in range(2):
        store.save(f"{i:02d}" * 32, _ds(i), {}, where="test")
    store.update_manifest("p", {"n": {"stage": "s"}})
    (root / "notes.txt").write_text("mine")  # the user's own file next to the store's
    assert main(["clean", "--cache", str(root)]) == 0
    out = capsys.readouterr().out
    assert f"removed 2 entries from {root}" in out and "kept 1 item(s) spflow does not manage: notes.txt" in out
    assert _tree(root) == ["notes.txt"]

    alone = Store(tmp_path / "alone")
    alone.save("ab" * 32, _ds(), {}, where="test")
    assert alone.clean() == 1 and not (tmp_path / "alone").exists()  # nothing else in it: the directory goes too
    assert Store(tmp_path / "never-created").clean() == 0


def test_a_store_made_before_the_marker_is_recognised_by_its_layout(tmp_path):
    store = Store(tmp_path / "old")
    store.save("ab" * 32, _ds(), {}, where="test")
    (tmp_path / "old" / MARKER).unlink()
    assert Store(tmp_path / "old").is_store()
    (tmp_path / "old" / "stray.txt").write_text("x")
    assert not Store(tmp_path / "old").is_store()
    (tmp_path / "old" / "stray.txt").unlink()
    assert Store(tmp_path / "old").clean() == 1 and not (tmp_path / "old").exists()


def test_clean_tmp_spares_entries_being_written(tmp_path):
    store = Store(tmp_path)
    store.save("ab" * 32, _ds(), {}, where="test")
    busy, stale = tmp_path / "tmp" / f"{'cd' * 32}.1", tmp_path / "tmp" / f"{'ef' * 32}.2"
    busy.mkdir()
    stale.mkdir()
    writer = Store(tmp_path)  # another process's view: it holds the lock of the entry it is writing
    assert writer.acquire("cd" * 32)
    assert store.clean(tmp_only=True) == 1
    assert busy.exists() and not stale.exists() and store.verify("ab" * 32)
    writer.release("cd" * 32)
    assert store.clean(tmp_only=True) == 1 and not busy.exists()


def test_a_rename_onto_a_complete_entry_of_another_writer_is_success(tmp_path):
    first, second = Store(tmp_path), Store(tmp_path)
    first.save("ab" * 32, _ds(1.0), {"writer": 1}, where="test")
    second._write("ab" * 32, _ds(1.0), {"writer": 2})  # lost the race: its rename finds the entry in place
    assert second.record("ab" * 32)["writer"] == 1 and second.verify("ab" * 32)
    assert list((tmp_path / "tmp").iterdir()) == []


def test_a_corrupt_leftover_is_replaced_by_a_new_save(tmp_path):
    store = Store(tmp_path)
    store.save("ab" * 32, _ds(1.0), {}, where="test")
    (store._entry("ab" * 32) / "data.nc").write_bytes(b"garbage")
    store.save("ab" * 32, _ds(2.0), {}, where="test")
    np.testing.assert_array_equal(Store(tmp_path).load("ab" * 32)["y"].values, np.full(4, 2.0))
    assert list((tmp_path / "tmp").iterdir()) == []


def test_clean_refuses_a_cache_a_run_is_writing(tmp_path):
    store = Store(tmp_path / "c")
    store.save("ab" * 32, _ds(), {}, where="test")
    writer = Store(tmp_path / "c")  # another process's view, computing a node under its key's lock
    assert writer.acquire("cd" * 32)
    with pytest.raises(CacheError, match=f"cache {tmp_path / 'c'} is in use: another process holds its lock 'cdcd"):
        store.clean()
    assert store.verify("ab" * 32)
    writer.release("cd" * 32)
    assert store.clean() == 1 and not (tmp_path / "c").exists()
