"""Where a stage's measured coreflood comes from: a bundled name, a file path, or a study experiment's mapping
``{"name", "data", "sha256", "attrs"}`` (:meth:`spflow.study.Experiment.observation_source`) — the data file plus the
metadata the study resolved for it (core with units, rate, schedule, measurement chain), which override the file's own
attrs. The ``observations`` and ``diagnose`` stages read their corefloods through :func:`load_observed`, so a study's
experiment reaches both with its study name and its declared core, whatever the file itself states."""

from __future__ import annotations

import hashlib
from collections.abc import Mapping
from pathlib import Path

import xarray as xr

from .coreflood import load_coreflood

__all__ = ["SOURCE_KEYS", "load_observed", "source_label"]

#: keys of a study experiment's observation mapping
SOURCE_KEYS = ("name", "data", "sha256", "attrs")


def source_label(source) -> str:
    """A short name of ``source`` for messages and attrs (the experiment name of a mapping, else the text)."""
    return str(source.get("name")) if isinstance(source, Mapping) else str(source)


def load_observed(source) -> xr.Dataset:
    """The coreflood Dataset of ``source`` (a bundled name, a path, or a study experiment's mapping).

    A mapping's ``attrs`` replace the file's attrs of the same name and its ``name`` becomes the ``experiment``
    attr; a ``sha256`` that differs from the file's bytes means the file changed after the study was read, which is
    refused. Raises ``ValueError`` naming the source and the field."""
    if not isinstance(source, Mapping):
        return load_coreflood(source)
    unknown = sorted(set(source) - set(SOURCE_KEYS))
    if unknown:
        raise ValueError(f"observation source {source_label(source)!r}: unknown key(s) {unknown}; allowed keys "
                         f"{list(SOURCE_KEYS)}")
    name, data = source.get("name"), source.get("data")
    if not isinstance(name, str) or not name.strip():
        raise ValueError(f"observation source: 'name' must be a non-empty string, got {name!r}")
    if not isinstance(data, str):
        raise ValueError(f"observation source {name!r}: 'data' must be the data file's path, got {data!r}")
    attrs = source.get("attrs", {})
    if not isinstance(attrs, Mapping):
        raise ValueError(f"observation source {name!r}: 'attrs' must be a mapping attr -> value, got "
                         f"{type(attrs).__name__}")
    file = Path(data)
    digest = source.get("sha256")
    if digest is not None and file.is_file() and hashlib.sha256(file.read_bytes()).hexdigest() != digest:
        raise ValueError(f"observation source {name!r}: data file {data!r} changed after the study was read "
                         "(its SHA-256 differs); load the study again")
    ds = load_coreflood(file)
    ds.attrs = dict(ds.attrs) | dict(attrs) | {"experiment": name}
    return ds
