"""Lab tables: small CSV files of one support experiment (thesis chapter 2), read with located errors.

Format (one experiment per file)::

    # kind: polymer_rheology
    # experiment: HPAM 3330 shear sweeps
    # units: c_polymer=ppm, salinity=ppm, shear_rate=1/s, viscosity=cp
    # temperature: 25 degC              <- any other "# key: value" line is kept as attrs["meta_<key>"]
    c_polymer,salinity,shear_rate,viscosity
    1000,9400,0.1,12.3
    ...

The ``# key: value`` lines come before the header row; after it, blank lines and lines starting with ``#`` are
skipped. Every value is numeric; an empty cell is NaN only in the columns the caller allows. Each required column
is converted from its declared unit to the caller's canonical unit (the first of its allowed units) with the factor
table :data:`UNITS`. Columns of the file that the caller does not ask for are ignored.

Every problem raises :class:`LabDataError` (a ``ValueError``) naming the file, the 1-based line and the column.
"""

from __future__ import annotations

import csv
import math
from collections.abc import Collection, Mapping
from pathlib import Path

import numpy as np
import xarray as xr

from spflow.core.errors import SpflowError

__all__ = ["LabDataError", "UNITS", "convert", "read_lab_table", "write_lab_table", "lab_meta"]

#: minimum number of data rows of a lab table
MIN_ROWS = 3
_RESERVED = ("kind", "experiment", "units")


class LabDataError(SpflowError, ValueError):
    """A lab table is malformed (names the file, the 1-based line and the column)."""


_DARCY_M2 = 9.869233e-13
#: normalised unit -> (dimension, factor to the dimension's base unit). Concentrations, fractions and mass ratios
#: share the dimensionless family (1 ppm = 1e-6 and 1 mg/l = 1e-6 for dilute aqueous solutions of density 1 g/ml,
#: 1 wt% = 1e-2; adsorbed mass per rock mass in mg/g or ug/g), so only the caller's allowed units decide what a
#: column may be given in.
UNITS: dict[str, tuple[str, float]] = {
    # dimensionless: fractions, concentrations, mass ratios
    "1": ("dimensionless", 1.0),
    "-": ("dimensionless", 1.0),
    "fraction": ("dimensionless", 1.0),
    "vol.frac.": ("dimensionless", 1.0),
    "wt.frac.": ("dimensionless", 1.0),
    "%": ("dimensionless", 1.0e-2),
    "wt%": ("dimensionless", 1.0e-2),
    "vol%": ("dimensionless", 1.0e-2),
    "ppm": ("dimensionless", 1.0e-6),
    "mg/l": ("dimensionless", 1.0e-6),
    "g/l": ("dimensionless", 1.0e-3),
    "mg/g": ("dimensionless", 1.0e-3),
    "ug/g": ("dimensionless", 1.0e-6),
    "mg/kg": ("dimensionless", 1.0e-6),
    # viscosity
    "cp": ("viscosity", 1.0e-3),
    "mpa.s": ("viscosity", 1.0e-3),
    "pa.s": ("viscosity", 1.0),
    # shear rate
    "1/s": ("rate", 1.0),
    "s^-1": ("rate", 1.0),
    "1/min": ("rate", 1.0 / 60.0),
    # interfacial tension
    "mn/m": ("tension", 1.0e-3),
    "dyn/cm": ("tension", 1.0e-3),
    "dyne/cm": ("tension", 1.0e-3),
    "n/m": ("tension", 1.0),
    # salinity in equivalents
    "meq/ml": ("equivalents", 1.0),
    "eq/l": ("equivalents", 1.0),
    "meq/l": ("equivalents", 1.0e-3),
    # length
    "m": ("length", 1.0),
    "cm": ("length", 1.0e-2),
    "mm": ("length", 1.0e-3),
    "ft": ("length", 0.3048),
    "in": ("length", 0.0254),
    "inch": ("length", 0.0254),
    # flow rate
    "ml/min": ("flow rate", 1.0e-6 / 60.0),
    "cc/min": ("flow rate", 1.0e-6 / 60.0),
    "ml/h": ("flow rate", 1.0e-6 / 3600.0),
    "ml/s": ("flow rate", 1.0e-6),
    "m3/s": ("flow rate", 1.0),
    # pressure (no megapascal: "MPa" and "mPa" differ only in case)
    "pa": ("pressure", 1.0),
    "kpa": ("pressure", 1.0e3),
    "bar": ("pressure", 1.0e5),
    "mbar": ("pressure", 1.0e2),
    "psi": ("pressure", 6894.757293168),
    "atm": ("pressure", 101325.0),
    # time
    "s": ("time", 1.0),
    "min": ("time", 60.0),
    "h": ("time", 3600.0),
    "day": ("time", 86400.0),
    # volume and pore volumes injected
    "ml": ("volume", 1.0e-6),
    "cc": ("volume", 1.0e-6),
    "l": ("volume", 1.0e-3),
    "m3": ("volume", 1.0),
    "pv": ("pore volumes", 1.0),
    # electrical conductivity
    "s/m": ("conductivity", 1.0),
    "ms/cm": ("conductivity", 0.1),
    "us/cm": ("conductivity", 1.0e-4),
    "ds/m": ("conductivity", 0.1),
    # permeability
    "m2": ("permeability", 1.0),
    "md": ("permeability", _DARCY_M2 * 1.0e-3),
    "d": ("permeability", _DARCY_M2),
    "darcy": ("permeability", _DARCY_M2),
    # density
    "g/cm3": ("density", 1.0e3),
    "g/ml": ("density", 1.0e3),
    "kg/m3": ("density", 1.0),
}


def _norm(unit: str) -> str:
    out = str(unit).strip().lower()
    for a, b in ((" ", ""), ("*", "."), ("\u00b7", "."), ("\u00b5", "u"), ("\u03bc", "u")):
        out = out.replace(a, b)
    return out


def _lookup(unit: str) -> tuple[str, float] | None:
    return UNITS.get(_norm(unit))


def _allowed(unit: str, allowed: tuple[str, ...]) -> bool:
    """``unit`` is one of ``allowed`` or an alias of one (same dimension and factor, e.g. dyn/cm and dyne/cm)."""
    entry = _lookup(unit)
    return entry is not None and any(_lookup(a) == entry for a in allowed)


def convert(values, from_unit: str, to_unit: str):
    """``values`` in ``from_unit`` expressed in ``to_unit`` (both in :data:`UNITS`, same dimension)."""
    src, dst = _lookup(from_unit), _lookup(to_unit)
    for unit, entry in ((from_unit, src), (to_unit, dst)):
        if entry is None:
            raise LabDataError(f"unknown unit {unit!r}; known units: {', '.join(sorted(UNITS))}")
    if src[0] != dst[0]:
        raise LabDataError(f"cannot convert {from_unit!r} ({src[0]}) to {to_unit!r} ({dst[0]})")
    return values * (src[1] / dst[1])


def _check_columns(columns: Mapping[str, tuple[str, ...]]) -> None:
    """The caller's column spec is itself valid (a programming error otherwise)."""
    if not columns:
        raise ValueError("read_lab_table: 'columns' must name at least one required column")
    for name, allowed in columns.items():
        if isinstance(allowed, str) or not allowed:
            raise ValueError(f"read_lab_table: column {name!r} needs a non-empty tuple of allowed units")
        dims = set()
        for unit in allowed:
            entry = _lookup(unit)
            if entry is None:
                raise ValueError(f"read_lab_table: column {name!r} allows unit {unit!r}, which is not in UNITS")
            dims.add(entry[0])
        if len(dims) > 1:
            raise ValueError(f"read_lab_table: column {name!r} allows units of different dimensions {sorted(dims)}")


def _parse_units(text: str, where: str) -> dict[str, str]:
    units = {}
    for item in text.split(","):
        if not item.strip():
            continue
        col, sep, unit = item.partition("=")
        if not sep or not col.strip() or not unit.strip():
            raise LabDataError(f"{where}: units entry {item.strip()!r} must read 'column=unit'")
        units[col.strip()] = unit.strip()
    return units


def read_lab_table(
    path,
    kind: str,
    columns: Mapping[str, tuple[str, ...]],
    *,
    allow_empty: Collection[str] = (),
) -> xr.Dataset:
    """Read a lab table into a Dataset on dim ``point``, every required column in its canonical unit.

    ``columns`` maps each required column to its allowed units, canonical first; ``allow_empty`` lists the columns
    whose empty cells are read as NaN. Returns one float variable per required column (``attrs["units"]`` = the
    canonical unit) and attrs ``kind``, ``experiment`` (default: the file stem), ``source`` and ``meta_<key>`` for
    the free ``# key: value`` lines. Raises :class:`LabDataError` naming the file, the line and the column.
    """
    _check_columns(columns)
    unknown_empty = set(allow_empty) - set(columns)
    if unknown_empty:
        raise ValueError(f"read_lab_table: allow_empty names columns not in 'columns': {sorted(unknown_empty)}")
    path = Path(path)
    if not path.is_file():
        raise LabDataError(f"lab table {str(path)!r}: no such file")
    with path.open(newline="", encoding="utf-8") as fh:
        lines = fh.read().splitlines()

    meta: dict[str, tuple[str, int]] = {}  # key -> (value, line)
    header: list[str] | None = None
    header_line = 0
    rows: list[tuple[int, list[str]]] = []
    for lineno, raw in enumerate(lines, 1):
        line = raw.strip()
        if not line:
            continue
        if line.startswith("#"):
            if header is None:
                key, sep, value = line[1:].partition(":")
                if sep and key.strip():
                    meta[key.strip().lower()] = (value.strip(), lineno)
            continue
        cells = [c.strip() for c in next(csv.reader([line]))]
        if header is None:
            header, header_line = cells, lineno
        else:
            rows.append((lineno, cells))

    name = f"lab table {str(path)!r}"
    kind_entry = meta.get("kind")
    if kind_entry is None:
        raise LabDataError(f"{name} line 1: missing '# kind: {kind}' header line")
    if kind_entry[0] != kind:
        raise LabDataError(f"{name} line {kind_entry[1]}: kind {kind_entry[0]!r} does not match the expected {kind!r}")
    if header is None:
        raise LabDataError(f"{name} line {len(lines)}: no header row of column names")
    units_entry = meta.get("units", ("", header_line))
    file_units = _parse_units(units_entry[0], f"{name} line {units_entry[1]}")

    index = {}
    for j, col in enumerate(header):
        if col in index:
            raise LabDataError(f"{name} line {header_line} column {col!r}: duplicate column name")
        index[col] = j
    for col, allowed in columns.items():
        if col not in index:
            raise LabDataError(
                f"{name} line {header_line} column {col!r}: missing required column (found {', '.join(header)})"
            )
        unit = file_units.get(col)
        if unit is None:
            raise LabDataError(
                f"{name} line {units_entry[1]} column {col!r}: no unit declared; add '{col}=<unit>' to the "
                f"'# units:' line (allowed: {', '.join(allowed)})"
            )
        if not _allowed(unit, allowed):
            raise LabDataError(
                f"{name} line {units_entry[1]} column {col!r}: unknown unit {unit!r}; allowed: {', '.join(allowed)}"
            )
    if len(rows) < MIN_ROWS:
        last = rows[-1][0] if rows else header_line
        raise LabDataError(f"{name} line {last}: {len(rows)} data rows, at least {MIN_ROWS} are needed")

    data = {col: np.empty(len(rows)) for col in columns}
    for i, (lineno, cells) in enumerate(rows):
        if len(cells) != len(header):
            raise LabDataError(f"{name} line {lineno}: {len(cells)} cells, the header has {len(header)} columns")
        for col in columns:
            text = cells[index[col]]
            if text == "":
                if col not in allow_empty:
                    raise LabDataError(f"{name} line {lineno} column {col!r}: empty cell (a number is required)")
                data[col][i] = math.nan
                continue
            try:
                value = float(text)
            except ValueError:
                raise LabDataError(f"{name} line {lineno} column {col!r}: {text!r} is not a number") from None
            if not math.isfinite(value):
                raise LabDataError(f"{name} line {lineno} column {col!r}: {text!r} is not finite")
            data[col][i] = value

    ds = xr.Dataset()
    for col, allowed in columns.items():
        ds[col] = xr.DataArray(convert(data[col], file_units[col], allowed[0]), dims=("point",),
                               attrs={"units": allowed[0]})
    ds.attrs["kind"] = kind
    ds.attrs["experiment"] = meta["experiment"][0] if "experiment" in meta else path.stem
    ds.attrs["source"] = str(path)
    for key, (value, _) in meta.items():
        if key not in _RESERVED:
            ds.attrs[f"meta_{key}"] = value
    return ds


def lab_meta(ds: xr.Dataset, key: str, units: tuple[str, ...] = ()) -> float:
    """Numeric metadata ``# key: value [unit]`` of a lab table, converted to ``units[0]`` (or unitless).

    ``units`` lists the allowed units, canonical first; with ``units=()`` the value must be a bare number.
    Raises :class:`LabDataError` naming the file and the key.
    """
    where = f"lab table {ds.attrs.get('source', '?')!r} metadata {key!r}"
    text = ds.attrs.get(f"meta_{key}")
    if text is None:
        raise LabDataError(f"{where}: missing; add a '# {key}: <value>' header line")
    number, _, unit = str(text).strip().partition(" ")
    try:
        value = float(number)
    except ValueError:
        raise LabDataError(f"{where}: {text!r} does not start with a number") from None
    if not math.isfinite(value):
        raise LabDataError(f"{where}: {text!r} is not finite")
    unit = unit.strip()
    if not units:
        if unit:
            raise LabDataError(f"{where}: {text!r} must be a bare number")
        return value
    if not _allowed(unit, units):
        raise LabDataError(f"{where}: unit {unit or '(none)'!r} not allowed; allowed: {', '.join(units)}")
    return float(convert(value, unit, units[0]))


def write_lab_table(ds: xr.Dataset, path, kind: str) -> Path:
    """Write the variables of ``ds`` on dim ``point`` in the lab-table format (inverse of :func:`read_lab_table`).

    Units come from each variable's ``attrs["units"]``; ``attrs["experiment"]`` and ``attrs["meta_<key>"]`` become
    header lines. NaN is written as an empty cell. Returns the path.
    """
    path = Path(path)
    cols = [str(v) for v in ds.data_vars if ds[v].dims == ("point",)]
    if not cols:
        raise ValueError("write_lab_table: the Dataset has no variables on dim 'point'")
    lines = [f"# kind: {kind}"]
    if "experiment" in ds.attrs:
        lines.append(f"# experiment: {ds.attrs['experiment']}")
    lines.append("# units: " + ", ".join(f"{c}={ds[c].attrs.get('units', '1')}" for c in cols))
    for key, value in ds.attrs.items():
        if key.startswith("meta_"):
            lines.append(f"# {key[5:]}: {value}")
    lines.append(",".join(cols))
    table = np.column_stack([np.asarray(ds[c].values, dtype=float) for c in cols])
    for row in table:
        lines.append(",".join("" if math.isnan(x) else f"{x:.10g}" for x in row))
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path
