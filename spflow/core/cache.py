"""Content-addressed result store: every version kept, atomic writes, checksummed reads, per-key locks.

Layout under the cache root (default ``.spflow/``)::

    spflow-store.json                  marker: this directory is a spflow store (format version)
    objects/<k[:2]>/<key>/data.nc      the node's output Dataset (netCDF)
    objects/<k[:2]>/<key>/meta.json    key, stage, version, params, inputs, sha256 of data.nc, timings
    pipelines/<name>.json              per pipeline: the provenance of each node's latest result (for ``status``)
    tmp/                               entries being written; renamed into ``objects/`` when complete
    locks/<name>.lock                  one lock file per key (and per pipeline manifest) for concurrent runs

An entry is written into ``tmp/`` and moved into place with one ``os.rename`` of its directory, so a crash leaves
either a complete entry or none. Files are not fsync'ed (it tripled the cost of a save): after a power loss an
entry whose blocks never reached the disk fails its checksum on the next read and is recomputed. Entries are immutable once in place: readers take no
lock. Writers of a key hold its lock (:mod:`spflow.core.locks`); a rename onto a complete entry that another writer
put there first is success. A read recomputes the sha256 of ``data.nc`` and refuses a mismatch.

The store only writes when it has something to store: reading a fully cached result needs no write permission. The
first write into a directory creates the marker; a directory holding anything else under the store's names is
refused, and :meth:`Store.clean` deletes only the store's own names, in a directory that carries the marker (or has
exactly the layout of a store made before the marker existed).
"""

from __future__ import annotations

import contextlib
import errno
import hashlib
import json
import os
import re
import shutil
import uuid
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr

from .errors import CacheError, SchemaError
from .locks import FileLock
from .netcdf_layout import DatasetLayout, read_layout

__all__ = ["Store", "CorruptEntryError", "MARKER", "STORE_FORMAT"]

#: The marker file naming a directory as a spflow store, and the layout version it records.
MARKER = "spflow-store.json"
STORE_FORMAT = 1
#: Everything the store creates under its root (``clean`` deletes these names and nothing else).
_MANAGED = ("objects", "pipelines", "tmp", "locks", MARKER)

_ATTR_TYPES = (str, int, float, np.integer, np.floating)
_KEY = re.compile(r"[0-9a-f]{64}")


class CorruptEntryError(Exception):
    """A stored entry failed its integrity check."""


def _file_sha256(path: Path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def _write_json_atomic(path: Path, obj: Any) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.name}.{uuid.uuid4().hex}.tmp")
    try:
        tmp.write_text(json.dumps(obj, indent=1, sort_keys=True, default=str))
        os.replace(tmp, path)
    finally:
        tmp.unlink(missing_ok=True)


def _check_attrs(where: str, attrs: dict) -> None:
    for name, value in attrs.items():
        ok = isinstance(value, _ATTR_TYPES) and not isinstance(value, (bool, np.bool_))
        if not ok and isinstance(value, (list, tuple, np.ndarray)):
            items = list(np.asarray(value).ravel()) if isinstance(value, np.ndarray) else list(value)
            ok = all(isinstance(v, _ATTR_TYPES) and not isinstance(v, (bool, np.bool_)) for v in items)
        if not ok:
            raise SchemaError(
                f"{where} attribute {name!r} = {value!r} cannot be stored in netCDF "
                "(allowed: str, int, float or lists of them)"
            )


def _check_serialisable(ds: xr.Dataset, where: str) -> None:
    _check_attrs(where, ds.attrs)
    for name, var in ds.variables.items():
        _check_attrs(f"{where} variable {name!r}", var.attrs)


def _describe_failure(exc: BaseException, root: Path, nbytes: int) -> str:
    """The cause of a failed write, in words: the error, and the free space when it cannot hold the result (the
    netCDF library reports a full disk as ``NetCDF: HDF error``)."""
    cause = str(exc) if isinstance(exc, OSError) and exc.strerror else f"{type(exc).__name__}: {exc}"
    if not (isinstance(exc, OSError) and exc.errno == errno.ENOSPC):
        with contextlib.suppress(OSError):
            free = shutil.disk_usage(root if root.exists() else root.parent).free
            if free < nbytes + (1 << 20):
                cause += f" (the file system has {free} bytes free for a {nbytes}-byte result: disk full)"
    return cause


def _legacy_layout(root: Path) -> bool:
    """A store written before the marker existed: only the store's names, ``objects/<2 hex>/<64 hex>``."""
    names = {p.name for p in root.iterdir()}
    if "objects" not in names or not names <= set(_MANAGED):
        return False
    for prefix in (root / "objects").iterdir():
        if not (prefix.is_dir() and re.fullmatch(r"[0-9a-f]{2}", prefix.name)):
            return False
        if not all(_KEY.fullmatch(entry.name) and entry.name.startswith(prefix.name) for entry in prefix.iterdir()):
            return False
    return True


class Store:
    """The on-disk store of node results."""

    def __init__(self, root: str | os.PathLike):
        self.root = Path(root)
        #: key -> (size, mtime_ns) of data.nc when its checksum last matched; a changed file is re-hashed.
        self._verified: dict[str, tuple[int, int]] = {}
        #: name -> [lock, depth] of the locks this object holds (re-entrant within the process).
        self._locks: dict[str, list] = {}
        self._initialised = False

    def _entry(self, key: str) -> Path:
        return self.root / "objects" / key[:2] / key

    # -- what a directory is -------------------------------------------------------------------------------------
    def is_store(self) -> bool:
        """True if the root carries the store marker, or has exactly the layout of an older spflow store."""
        marker = self.root / MARKER
        if marker.is_file():
            return True
        return self.root.is_dir() and _legacy_layout(self.root)

    def _initialise(self) -> None:
        """Before the first write: make the root a store (marker), refusing a directory that holds other things under
        the store's names."""
        if self._initialised:
            return
        marker = self.root / MARKER
        if marker.is_file():
            try:
                found = json.loads(marker.read_text()).get("format")
            except (OSError, ValueError, AttributeError):
                found = None
            if found != STORE_FORMAT:
                raise CacheError(f"cache {self.root}: {MARKER} records store format {found!r}; this spflow writes "
                                 f"format {STORE_FORMAT} (use another --cache directory)")
            self._initialised = True
            return
        if self.root.is_dir() and not _legacy_layout(self.root):
            names = {p.name for p in self.root.iterdir()}
            clash = sorted(names & set(_MANAGED)) if MARKER not in names else []  # (another run may just have made it)
            if clash:
                raise CacheError(f"{self.root} is not a spflow cache (no {MARKER}) but holds {clash}; refusing to "
                                 "write into it: choose another --cache directory")
        self.root.mkdir(parents=True, exist_ok=True)
        _write_json_atomic(marker, {"format": STORE_FORMAT, "store": "spflow result store",
                                    "layout": "objects/<key[:2]>/<key>/{data.nc,meta.json}"})
        self._initialised = True

    # -- locks ---------------------------------------------------------------------------------------------------
    def acquire(self, name: str, *, blocking: bool = True, waiting: str = "") -> bool:
        """Take the inter-process lock ``name`` (a key, or ``pipeline-<name>``); re-entrant within this object.

        Returns False without waiting if ``blocking`` is False and another process holds it."""
        held = self._locks.get(name)
        if held is not None:
            held[1] += 1
            return True
        self._initialise()
        (self.root / "locks").mkdir(exist_ok=True)
        lock = FileLock(self.root / "locks" / f"{name}.lock", waiting=waiting)
        if not lock.acquire(blocking=blocking):
            return False
        self._locks[name] = [lock, 1]
        return True

    def release(self, name: str) -> None:
        held = self._locks[name]
        held[1] -= 1
        if held[1] == 0:
            del self._locks[name]
            held[0].release()

    @contextlib.contextmanager
    def locked(self, name: str, waiting: str = "") -> Iterator[None]:
        self.acquire(name, waiting=waiting)
        try:
            yield
        finally:
            self.release(name)

    # -- entries -------------------------------------------------------------------------------------------------
    def has(self, key: str) -> bool:
        return (self._entry(key) / "meta.json").is_file()

    def record(self, key: str) -> dict[str, Any]:
        return json.loads((self._entry(key) / "meta.json").read_text())

    def verify(self, key: str) -> bool:
        """True if the entry exists and its data file matches the recorded checksum.

        The file is hashed once per store object; later calls re-hash only if its size or mtime changed.
        """
        data = self._entry(key) / "data.nc"
        try:
            st = data.stat()
            stamp = (st.st_size, st.st_mtime_ns)
            if self._verified.get(key) == stamp:
                return True
            ok = _file_sha256(data) == self.record(key)["sha256"]
        except (OSError, ValueError, KeyError, TypeError):
            return False
        if ok:
            self._verified[key] = stamp
        return ok

    def load(self, key: str) -> xr.Dataset:
        """Load an entry fully into memory; raise :class:`CorruptEntryError` if its checksum does not match."""
        if not self.verify(key):
            raise CorruptEntryError(f"cache entry {key} is missing or fails its checksum")
        with xr.open_dataset(self._entry(key) / "data.nc", engine="netcdf4") as ds:
            return ds.load()

    def layout(self, key: str) -> DatasetLayout:
        """The entry's dims, variables (dims, dtypes, attributes) and attributes, without reading the arrays: from the
        file's header (:func:`~spflow.core.netcdf_layout.read_layout`), or, for an encoding the header reader leaves
        to xarray, from the Dataset xarray opens lazily. Raises ``OSError``/``ValueError`` if it cannot be read."""
        data = self._entry(key) / "data.nc"
        found = read_layout(data)
        if found is not None:
            return found
        with xr.open_dataset(data, engine="netcdf4") as ds:
            return DatasetLayout.of(ds)

    def save(self, key: str, ds: xr.Dataset, meta: dict[str, Any], *, where: str) -> None:
        """Write ``ds`` and its metadata atomically under ``key``'s lock; an existing complete entry is kept as is.

        Any failure to write (full disk, read-only or vanished directory, the netCDF library's I/O errors) raises
        :class:`CacheError` naming ``where``, the cache and the cause; nothing half-written is left in ``objects/``
        and the temporary entry is removed."""
        _check_serialisable(ds, where)
        if self.verify(key):
            return
        try:
            with self.locked(key):
                if not self.verify(key):
                    self._write(key, ds, meta)
        except (OSError, RuntimeError) as exc:
            raise CacheError(f"{where}: cannot store the result in cache {self.root}: "
                             f"{_describe_failure(exc, self.root, ds.nbytes)}") from exc

    def _write(self, key: str, ds: xr.Dataset, meta: dict[str, Any]) -> None:
        tmp = self.root / "tmp" / f"{key}.{uuid.uuid4().hex}"
        tmp.mkdir(parents=True)
        try:
            data = tmp / "data.nc"
            ds.drop_encoding().to_netcdf(data, engine="netcdf4")
            record = dict(meta, key=key, sha256=_file_sha256(data), nbytes=data.stat().st_size)
            (tmp / "meta.json").write_text(json.dumps(record, indent=1, sort_keys=True, default=str))
            final = self._entry(key)
            final.parent.mkdir(parents=True, exist_ok=True)
            try:
                os.rename(tmp, final)
            except OSError as exc:
                if exc.errno not in (errno.EEXIST, errno.ENOTEMPTY):
                    raise
                if self.verify(key):
                    return  # another writer put a complete entry there first: ours is redundant
                # a corrupt leftover (we hold the key's lock, so nobody is writing it): move it aside, then ours in
                aside = self.root / "tmp" / f"{key}.{uuid.uuid4().hex}.old"
                os.rename(final, aside)
                os.rename(tmp, final)
                shutil.rmtree(aside, ignore_errors=True)
        finally:
            if tmp.exists():
                shutil.rmtree(tmp, ignore_errors=True)

    def discard(self, key: str) -> None:
        """Remove an entry (callers hold its lock)."""
        self._verified.pop(key, None)
        entry = self._entry(key)
        if entry.exists():
            aside = self.root / "tmp" / f"{key}.{uuid.uuid4().hex}.old"
            aside.parent.mkdir(parents=True, exist_ok=True)
            os.rename(entry, aside)  # one atomic step out of objects/, then the slow delete
            shutil.rmtree(aside, ignore_errors=True)

    # -- per-pipeline manifests (what ran last, for staleness explanations) -------------------------------------------
    def _manifest_path(self, pipeline: str) -> Path:
        return self.root / "pipelines" / f"{pipeline}.json"

    def manifest(self, pipeline: str) -> dict[str, Any]:
        try:
            return json.loads(self._manifest_path(pipeline).read_text())
        except (OSError, ValueError):
            return {}

    def update_manifest(self, pipeline: str, provenances: dict[str, dict[str, Any]]) -> None:
        """Record the provenance of these nodes' latest results (one atomic rewrite under the manifest's lock).

        Nothing is written when the manifest already says so (a fully cached run needs no write access). Raises
        ``OSError`` if the write fails; callers treat the manifest as best-effort."""
        if not provenances:
            return
        current = self.manifest(pipeline)
        if _json_equal({**current, **provenances}, current):
            return
        with self.locked(f"pipeline-{pipeline}"):
            _write_json_atomic(self._manifest_path(pipeline), {**self.manifest(pipeline), **provenances})

    # -- clean ---------------------------------------------------------------------------------------------------
    def clean(self, *, tmp_only: bool = False) -> int:
        """Delete what the store manages (or only unfinished temporary entries); return the number of entries removed.

        Refuses (:class:`CacheError`) a directory that is not a spflow store, naming it. Only the store's own names
        are deleted; the root itself goes only if that leaves it empty. A store another process is writing (one of its
        locks held) is refused; ``tmp_only`` instead skips the temporary entries whose key is locked."""
        if not self.root.exists():
            return 0
        if not self.root.is_dir() or not self.is_store():
            if self.root.is_dir() and not any(self.root.iterdir()):
                return 0
            raise CacheError(f"{self.root} is not a spflow cache (no {MARKER}, and not the layout objects/<2 hex>/"
                             "<key>/); refusing to delete anything in it")
        if tmp_only:
            return self._clean_tmp()
        self._refuse_if_in_use()
        objects = self.root / "objects"
        count = sum(1 for p in objects.glob("*/*") if p.is_dir()) if objects.is_dir() else 0
        for name in _MANAGED:
            path = self.root / name
            if path.is_symlink() or path.is_file():
                path.unlink()
            elif path.is_dir():
                shutil.rmtree(path)
        with contextlib.suppress(OSError):
            self.root.rmdir()  # only if nothing else is in it
        self._verified.clear()
        self._initialised = False
        return count

    def _refuse_if_in_use(self) -> None:
        """Probe every lock of the store without waiting (one at a time: a large store has many); refuse to clean if
        another process holds one (a run is writing). A run starting after the probe is not stopped: its writes
        recreate the store."""
        for name in sorted({p.name.split(".lock")[0] for p in (self.root / "locks").glob("*.lock*")}):
            if not self.acquire(name, blocking=False):
                raise CacheError(f"cache {self.root} is in use: another process holds its lock {name!r} (a run is "
                                 "writing a result); nothing was deleted, clean it when the run has finished")
            self.release(name)

    def _clean_tmp(self) -> int:
        tmp = self.root / "tmp"
        if not tmp.is_dir():
            return 0
        count = 0
        for path in tmp.iterdir():
            key = path.name.split(".")[0]
            if _KEY.fullmatch(key) and not path.name.endswith(".old"):
                if not self.acquire(key, blocking=False):
                    continue  # being written by a running process
                try:
                    shutil.rmtree(path, ignore_errors=True)
                finally:
                    self.release(key)
            elif path.is_dir():
                shutil.rmtree(path, ignore_errors=True)
            else:
                path.unlink(missing_ok=True)
            count += 1
        return count


def _json_equal(a: Any, b: Any) -> bool:
    """Equality of two JSON-able objects as they would be stored (tuples and lists alike, keys as strings)."""
    def dump(obj: Any) -> str:
        return json.dumps(obj, sort_keys=True, default=str)

    return dump(a) == dump(b)
