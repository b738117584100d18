"""The cache under hostile conditions: a read-only cache, a full disk, a forged entry. Observed through the run's
results, the execution log, the store's contents and the exact one-line errors and warnings."""

import contextlib
import errno
import hashlib
import io
import json
import multiprocessing
import os
import resource
import shutil
import signal
import textwrap
import warnings

import numpy as np
import pytest
import xarray as xr
from helpers import chain
from toy_stages import executions

import spflow
from spflow.core.cache import Store
from spflow.core.errors import CacheError, CacheWarning

ALL = ["a", "b", "c", "d", "e"]


@contextlib.contextmanager
def read_only(root, monkeypatch):
    """Every attempt to create, write, rename or delete anything under ``root`` fails with EROFS, as on a read-only
    mount; works as root (the CI user), for whom ``chmod -w`` stops nothing. Yields the list of attempts."""
    root = os.path.realpath(root)
    attempts = []

    def inside(path):
        return isinstance(path, (str, bytes, os.PathLike)) and os.path.realpath(os.fsdecode(path)).startswith(root)

    def refuse(what, path):
        attempts.append((what, os.fsdecode(path)))
        raise OSError(errno.EROFS, os.strerror(errno.EROFS), os.fsdecode(path))

    def guard(name, module, check=lambda *a, **k: True):
        real = getattr(module, name)

        def fake(path, *args, **kwargs):
            if inside(path) and check(*args, **kwargs):
                refuse(name, path)
            return real(path, *args, **kwargs)

        monkeypatch.setattr(module, name, fake)

    writes = os.O_WRONLY | os.O_RDWR | os.O_CREAT | os.O_TRUNC | os.O_APPEND
    guard("open", os, lambda flags, *a, **k: flags & writes)
    guard("open", io, lambda mode="r", *a, **k: any(c in mode for c in "wax+"))
    for name in ("rename", "replace", "unlink", "remove", "rmdir"):
        guard(name, os)
    real_mkdir = os.mkdir

    def mkdir(path, *args, **kwargs):
        if inside(path) and os.path.exists(path):
            raise FileExistsError(errno.EEXIST, os.strerror(errno.EEXIST), os.fsdecode(path))  # as the kernel says
        if inside(path):
            refuse("mkdir", path)
        return real_mkdir(path, *args, **kwargs)

    monkeypatch.setattr(os, "mkdir", mkdir)
    guard("rmtree", shutil)
    real_to_netcdf = xr.Dataset.to_netcdf

    def to_netcdf(self, path=None, *args, **kwargs):
        if inside(path):
            refuse("to_netcdf", path)
        return real_to_netcdf(self, path, *args, **kwargs)

    monkeypatch.setattr(xr.Dataset, "to_netcdf", to_netcdf)
    yield attempts


def test_a_fully_cached_run_needs_no_write_access(toys, log, cache, monkeypatch):
    first = spflow.run(chain(str(log)), cache=cache)
    expected = {n: first[n]["y"].values.copy() for n in ALL}
    with read_only(cache, monkeypatch) as attempts, warnings.catch_warnings():
        warnings.simplefilter("error")
        again = spflow.run(chain(str(log)), cache=cache)
        assert sorted(again.cached) == ALL and again.executed == []
        for n in ALL:
            np.testing.assert_array_equal(again[n]["y"].values, expected[n])
        assert all(s.fresh for s in spflow.status(chain(str(log)), cache=cache))
    assert attempts == []  # not one write was even tried


def test_a_read_only_cache_warns_about_the_manifest_and_names_the_node_it_cannot_store(toys, log, cache, monkeypatch):
    spflow.run(chain(str(log)), cache=cache)
    renamed = chain(str(log))
    renamed.name = "chain_copy"  # same nodes, another pipeline: its manifest would be new
    with read_only(cache, monkeypatch):
        with pytest.warns(CacheWarning, match=f"could not update the manifest of pipeline 'chain_copy' in cache {cache}"):
            result = spflow.run(renamed, cache=cache)
        assert sorted(result.cached) == ALL
        with pytest.raises(CacheError) as info:
            spflow.run(chain(str(log), factor=4.0), cache=cache)
    assert str(info.value).startswith(f"node 'b': cannot lock its cache entry in {cache}: [Errno 30] Read-only "
                                      f"file system: '{cache / 'locks'}/")


@pytest.mark.skipif(os.geteuid() == 0, reason="root writes through chmod -w; the EROFS simulation covers it")
def test_a_fully_cached_run_works_on_a_chmod_read_only_cache(toys, log, cache):
    spflow.run(chain(str(log)), cache=cache)
    dirs = [cache, *[p for p in cache.rglob("*") if p.is_dir()]]
    for d in dirs:
        d.chmod(0o555)
    try:
        assert sorted(spflow.run(chain(str(log)), cache=cache).cached) == ALL
    finally:
        for d in dirs:
            d.chmod(0o755)


def test_a_full_disk_names_node_cache_and_cause_and_keeps_finished_entries(toys, log, cache, monkeypatch, tmp_path,
                                                                          capsys):
    real_to_netcdf = xr.Dataset.to_netcdf
    saves = []

    def fills_the_disk(self, path, *args, **kwargs):
        saves.append(path)
        if len(saves) < 4:  # a, d and b fit; c does not
            return real_to_netcdf(self, path, *args, **kwargs)
        with open(path, "wb") as fh:
            fh.write(b"\x89HDF\r\n")  # half-written
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), str(path))

    monkeypatch.setattr(xr.Dataset, "to_netcdf", fills_the_disk)
    (tmp_path / "chain_cli.py").write_text(textwrap.dedent(f"""
        import sys
        sys.path.insert(0, {os.path.dirname(__file__)!r})
        from helpers import chain
        pipeline = chain({str(log)!r})
        """))
    from spflow.cli import main

    assert main(["run", str(tmp_path / "chain_cli.py"), "--cache", str(cache)]) == 2
    err = capsys.readouterr().err.splitlines()
    assert "Traceback" not in "\n".join(err) and not err[-1].startswith("[spflow]")  # progress, then one line:
    assert err[-1].startswith(f"spflow: error: node 'c' (stage 'toy_scale') output: cannot store the result in cache "
                          f"{cache}: [Errno 28] No space left on device: ")
    store = Store(cache)
    keys = {s.node: s.key for s in spflow.status(chain(str(log)), cache=cache)}
    assert all(store.verify(keys[n]) for n in "abd") and not store.has(keys["c"])
    assert list((cache / "tmp").iterdir()) == []  # nothing half-written is left
    monkeypatch.setattr(xr.Dataset, "to_netcdf", real_to_netcdf)
    log.unlink()
    result = spflow.run(chain(str(log)), cache=cache)
    assert sorted(result.executed) == ["c", "e"] and sorted(executions(log)) == ["add", "scale:3.0"]


def _save_beyond_a_file_size_limit(root, queue):
    store = Store(root)
    store.save("aa" * 32, xr.Dataset({"y": ("x", np.arange(10.0))}), {}, where="node 'small'")
    signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
    resource.setrlimit(resource.RLIMIT_FSIZE, (100_000, resource.getrlimit(resource.RLIMIT_FSIZE)[1]))
    try:
        store.save("bb" * 32, xr.Dataset({"y": ("x", np.linspace(0.0, 1.0, 200_000))}), {}, where="node 'big'")
        queue.put("saved")
    except BaseException as exc:  # noqa: BLE001 - the parent inspects what came out
        queue.put(f"{type(exc).__name__}: {exc}")


def test_a_real_write_failure_inside_the_netcdf_library_is_one_cache_error(tmp_path):
    """The netCDF library, not Python, hits the limit (a file-size rlimit, in a forked process, stands in for a full
    disk, which needs a mount): its bare ``RuntimeError: NetCDF: HDF error`` becomes one line naming the node and the
    cache."""
    fork = multiprocessing.get_context("fork")
    queue = fork.Queue()
    child = fork.Process(target=_save_beyond_a_file_size_limit, args=(tmp_path / "c", queue))
    child.start()
    outcome = queue.get(timeout=120)
    child.join(30)
    assert outcome.startswith(f"CacheError: node 'big': cannot store the result in cache {tmp_path / 'c'}: ")
    assert "\n" not in outcome
    store = Store(tmp_path / "c")
    assert store.verify("aa" * 32) and not store.has("bb" * 32)
    assert list((tmp_path / "c" / "tmp").iterdir()) == []


def test_an_entry_with_a_forged_checksum_and_another_schema_is_rejected(toys, log, cache):
    first = spflow.run(chain(str(log)), cache=cache)
    expected = first["c"]["y"].values.copy()
    entry = Store(cache)._entry(first.keys["c"])
    forged = xr.Dataset({"z": ("t", np.zeros(3), {"units": "s"})})  # another node's schema
    (entry / "data.nc").unlink()
    forged.to_netcdf(entry / "data.nc")
    record = json.loads((entry / "meta.json").read_text())
    record["sha256"] = hashlib.sha256((entry / "data.nc").read_bytes()).hexdigest()  # the checksum is rewritten
    (entry / "meta.json").write_text(json.dumps(record))
    assert Store(cache).verify(first.keys["c"])  # the checksum alone is fooled
    by_node = {s.node: s for s in spflow.status(chain(str(log)), cache=cache)}
    assert not by_node["c"].fresh and "does not match the output schema" in by_node["c"].reasons[0]
    log.unlink()
    with pytest.warns(spflow.CacheIntegrityWarning,
                      match=r"node 'c' does not match the output schema of its stage \(stage 'toy_scale' port "
                            r"'output': expected dims \['x'\], found \['t'\]"):
        result = spflow.run(chain(str(log)), cache=cache)
    assert result.executed == ["c"] and executions(log) == ["scale:3.0"]
    np.testing.assert_array_equal(result["c"]["y"].values, expected)


def test_an_entry_moved_under_another_key_is_rejected(toys, log, cache):
    first = spflow.run(chain(str(log)), cache=cache)
    store = Store(cache)
    a, c = store._entry(first.keys["a"]), store._entry(first.keys["c"])
    shutil.rmtree(c)
    shutil.copytree(a, c)  # a whole, self-consistent entry of node 'a' (same schema) under c's key
    log.unlink()
    with pytest.warns(spflow.CacheIntegrityWarning, match=f"node 'c' records key {first.keys['a'][:12]}"):
        result = spflow.run(chain(str(log)), cache=cache)
    assert result.executed == ["c"]
