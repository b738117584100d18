"""``load_coreflood``: bundled names, netCDF files and lab CSV files, all returned in the coreflood format."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import xarray as xr

from spflow import datasets

from .csv_table import read_csv
from .format import check_coreflood, schedule_json
from .metadata import check_metadata
from .schedule_file import read_schedule_file

__all__ = ["load_coreflood"]


def _schedule_text(schedule, base: Path | None, where: str) -> str:
    """JSON text of ``schedule``: a Table 2.5 name, a ``.toml`` path (relative to ``base``), or a Schedule/slugs."""
    if isinstance(schedule, (str, Path)) and str(schedule).lower().endswith(".toml"):
        file = Path(schedule)
        if not file.is_absolute() and base is not None:
            file = base / file
        return schedule_json(read_schedule_file(file))
    try:
        return schedule_json(schedule)
    except ValueError as exc:
        raise ValueError(f"{where}: schedule: {exc}") from None


def load_coreflood(path_or_name, *, units=None, schedule=None, columns=None) -> xr.Dataset:
    """Load a coreflood: a bundled name (``"BCF1"``, ``"BCF2"``, ``"BCF3"``), a netCDF file (``.nc``) in the
    coreflood format, or a CSV file (``.csv``; layout in :mod:`spflow.io.csv_table`).

    ``units`` (``{column: unit}``) and ``columns`` (``{file column: spflow column or None}``) apply to CSV files
    and override the file's header. ``schedule`` (a Table 2.5 name, a TOML schedule file, a Schedule or a list
    of slug mappings) overrides the file's schedule; it is stored as JSON text in the ``schedule`` attr.
    Invalid files raise ``ValueError`` naming the file, the row/line and the column (or the attr); the metadata
    attrs (core data, volumes, schedule, measurement model) are validated by :func:`spflow.io.metadata.check_metadata`
    for both file types, and empty, binary or non-UTF-8 files are named as such.
    """
    text = str(path_or_name)
    if text.strip().upper() in datasets.NAMES and not Path(text).exists():
        file = datasets.path(text)
    else:
        file = Path(path_or_name)
    where = f"file {str(file)!r}"
    if not file.is_file():
        raise ValueError(f"{where}: no such file (and not a bundled dataset name: {', '.join(datasets.NAMES)})")
    suffix = file.suffix.lower()
    if suffix in (".nc", ".nc4", ".netcdf"):
        if units is not None or columns is not None:
            raise ValueError(f"{where}: units= and columns= apply to CSV files only (netCDF carries its units)")
        ds = check_coreflood(_open_netcdf(file, where), where)
        file_schedule = None
    elif suffix == ".csv":
        if units is not None and not isinstance(units, Mapping):
            raise ValueError(f"units must be a mapping column -> unit, got {type(units).__name__}")
        if columns is not None and not isinstance(columns, Mapping):
            raise ValueError(f"columns must be a mapping file column -> spflow column, got {type(columns).__name__}")
        ds, file_schedule = read_csv(file, units=units, columns=columns)
    else:
        raise ValueError(f"{where}: unknown file type {suffix!r}; allowed: .nc (netCDF), .csv")
    chosen = schedule if schedule is not None else file_schedule
    if chosen is not None:
        ds.attrs["schedule"] = _schedule_text(chosen, file.parent, where)
    ds.attrs = check_metadata(ds.attrs, where)
    return ds


def _open_netcdf(file: Path, where: str) -> xr.Dataset:
    """The Dataset of netCDF ``file``, loaded into memory; an unreadable file is a ``ValueError`` naming it."""
    if file.stat().st_size == 0:
        raise ValueError(f"{where}: empty file; expected a netCDF coreflood (format of docs/data.md)")
    try:
        with xr.open_dataset(file) as opened:
            return opened.load().drop_encoding()
    except Exception as exc:  # noqa: BLE001 -- xarray/netCDF4/h5py report unreadable files through many types
        raise ValueError(f"{where}: not a readable netCDF file ({type(exc).__name__}); expected a netCDF coreflood "
                         "(format of docs/data.md)") from None
