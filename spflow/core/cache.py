"""Content-addressed result store: every version kept, atomic writes, checksummed reads.

Layout under the cache root (default ``.spflow/``)::

    objects/<k[:2]>/<key>/data.nc      the node's output Dataset (netCDF)
    objects/<k[:2]>/<key>/meta.json    key, stage, version, params, inputs, sha256 of data.nc, timings
    pipelines/<name>.json              per pipeline: the provenance of each node's latest result (for ``status``)
    tmp/                               entries being written; renamed into ``objects/`` when complete

An entry is written into ``tmp/`` and moved into place with one ``os.rename`` of its directory, so a crash leaves
either a complete entry or none. A read recomputes the sha256 of ``data.nc`` and refuses a mismatch.
"""

from __future__ import annotations

import hashlib
import json
import os
import shutil
import uuid
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr

from .errors import SchemaError

__all__ = ["Store", "CorruptEntryError"]

_ATTR_TYPES = (str, int, float, np.integer, np.floating)


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
    tmp.write_text(json.dumps(obj, indent=1, sort_keys=True, default=str))
    os.replace(tmp, path)


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


class Store:
    """The on-disk store of node results."""

    def __init__(self, root: str | os.PathLike):
        self.root = Path(root)
        #: key -> (size, mtime_ns) of data.nc when its checksum last matched; a changed file is re-hashed.
        self._verified: dict[str, tuple[int, int]] = {}

    def _entry(self, key: str) -> Path:
        return self.root / "objects" / key[:2] / key

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
        except (OSError, ValueError, KeyError):
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

    def save(self, key: str, ds: xr.Dataset, meta: dict[str, Any], *, where: str) -> None:
        """Write ``ds`` and its metadata atomically; an existing complete entry is kept as is."""
        _check_serialisable(ds, where)
        if self.has(key):
            return
        tmp = self.root / "tmp" / f"{key}.{uuid.uuid4().hex}"
        tmp.mkdir(parents=True)
        try:
            data = tmp / "data.nc"
            ds.drop_encoding().to_netcdf(data, engine="netcdf4")
            record = dict(meta, key=key, sha256=_file_sha256(data), nbytes=data.stat().st_size)
            (tmp / "meta.json").write_text(json.dumps(record, indent=1, sort_keys=True, default=str))
            final = self._entry(key)
            final.parent.mkdir(parents=True, exist_ok=True)
            if final.exists():  # a corrupt leftover (has() was False): replace it
                shutil.rmtree(final)
            os.rename(tmp, final)
        finally:
            if tmp.exists():
                shutil.rmtree(tmp, ignore_errors=True)

    def discard(self, key: str) -> None:
        self._verified.pop(key, None)
        shutil.rmtree(self._entry(key), ignore_errors=True)

    # -- per-pipeline manifests (what ran last, for staleness explanations) -------------------------------------------
    def _manifest_path(self, pipeline: str) -> Path:
        return self.root / "pipelines" / f"{pipeline}.json"

    def manifest(self, pipeline: str) -> dict[str, Any]:
        try:
            return json.loads(self._manifest_path(pipeline).read_text())
        except (OSError, ValueError):
            return {}

    def update_manifest(self, pipeline: str, provenances: dict[str, dict[str, Any]]) -> None:
        """Record the provenance of these nodes' latest results (one atomic rewrite)."""
        if provenances:
            _write_json_atomic(self._manifest_path(pipeline), {**self.manifest(pipeline), **provenances})

    def clean(self, *, tmp_only: bool = False) -> int:
        """Delete the store (or only unfinished temporary entries); return the number of entries removed."""
        target = self.root / "tmp" if tmp_only else self.root
        if not target.exists():
            return 0
        count = sum(1 for _ in target.glob("*")) if tmp_only else sum(1 for _ in (self.root / "objects").glob("*/*"))
        shutil.rmtree(target)
        return count
