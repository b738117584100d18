"""Read a lab coreflood CSV file into the coreflood format (:mod:`spflow.io.format`).

File layout (``docs/data.md``)::

    # experiment: my_flood              optional header lines "# key: value" before the column names
    # schedule: my_flood.toml           a Table 2.5 name or a TOML schedule file (relative to the CSV)
    # pore_volume_ml: 71.0              needed to derive oil_cut from oil_volume
    # ooip_ml: 56.8                     needed to derive recovery from oil_volume
    # units: dp=kPa, recovery=%         units per (spflow) column; defaults Pa, PV, fraction, ml, ppm
    # columns: Inj PV=pv, dP=dp         file column -> spflow column
    # noise_pressure_relative: 0.02     measurement-noise attrs (any NoiseModel field, with prefix noise_)
    # core_length: 30 cm                core data with units (core_length, core_diameter, permeability, rate,
    # porosity: 0.19                    porosity, swi) or in the format's units (core_length_m, ..., qinj_ml_min;
    # rate_ml_min: 0.5                  rate_ml_min is qinj_ml_min), stored as the attrs of spflow.io.metadata
    pv,dp,oil_cut,recovery
    0.02,7830,,
    0.05,7790,1.0,0.0625

Columns: ``pv`` (required, injected PV; strictly increasing), ``dp``, ``oil_cut``, ``recovery``, ``oil_volume``,
``c_polymer_out``, ``c_surfactant_out``, ``salinity_out``. An empty cell means "not measured at this PV". A row with
a tube column filled is a tube ending at its ``pv``; the tube starts at the previous tube's end (0 for the first);
tube rows whose first tube is half the size of the others (the pattern tube midpoints make) are read so all the
same, with a warning and the attr ``tube_rows_note``. Other header keys are kept as ``meta_<key>`` attrs. Errors are
``ValueError`` naming the file, the line (1-based, as an editor shows it) and the column. The file must be UTF-8
text; empty, binary and UTF-16 files are named as such. PV must lie in ``[0, MAX_PV]``, ``dp`` must not be negative
and ``recovery`` must not decrease.
"""

from __future__ import annotations

import csv
import math
import warnings
from dataclasses import fields
from pathlib import Path

import numpy as np
import xarray as xr

from spflow.synthetic.noise_model import NoiseModel

from .format import MAX_PV, TUBE_VARIABLES, VARIABLES, build_coreflood
from .lab_units import ALLOWED_UNITS, DEFAULT_UNITS, factor
from .metadata import core_unit
from .quantities import VELOCITY_UNITS, parse_quantity, velocity_to_rate
from .text_file import read_utf8_text

__all__ = ["read_csv", "TUBE_ROWS_NOTE"]

_COLUMNS = tuple(ALLOWED_UNITS)
#: the attr holding the loader's remark on tube rows that look like tube midpoints (:func:`_looks_like_midpoints`)
TUBE_ROWS_NOTE = "tube_rows_note"
_FLOAT_KEYS = {"pore_volume_ml", "ooip_ml"} | {f"noise_{f.name}" for f in fields(NoiseModel)}
_TEXT_KEYS = {"experiment", "schedule", "source", "units", "columns"}
_VOLUME_KEYS = ("oil_cut", "recovery", "oil_volume")
#: header key with units -> (core attr, quantity kind)
_CORE_KEYS = {"core_length": ("core_length_m", "length"), "core_diameter": ("core_diameter_m", "length"),
              "permeability": ("permeability_md", "permeability"), "rate": ("qinj_ml_min", "rate"),
              "porosity": ("porosity", "fraction"), "swi": ("swi", "fraction")}
#: header key in the format's units -> core attr
_CORE_PLAIN = {"core_length_m": "core_length_m", "core_diameter_m": "core_diameter_m",
               "permeability_md": "permeability_md", "qinj_ml_min": "qinj_ml_min", "rate_ml_min": "qinj_ml_min"}


def _core_value(key: str, value: str, at: str):
    """``(core attr, value in the format's unit or (velocity, unit) for a rate given as a velocity)``."""
    if key in _CORE_PLAIN:
        attr = _CORE_PLAIN[key]
        try:
            return attr, float(value)
        except ValueError:
            raise ValueError(f"{at}: {value.strip()!r} is not a number (in {core_unit(attr)!r}; for other units "
                             f"use the key {next(k for k, (a, _) in _CORE_KEYS.items() if a == attr)!r})") from None
    attr, kind = _CORE_KEYS[key]
    x, unit = parse_quantity(value.strip(), kind, at)
    return attr, ((x, unit) if unit in VELOCITY_UNITS else x)


def _pairs(text: str, where: str) -> dict[str, str]:
    out = {}
    for item in filter(None, (part.strip() for part in text.split(","))):
        key, sep, value = item.partition("=")
        if not sep or not key.strip() or not value.strip():
            raise ValueError(f"{where}: expected 'name=value' items separated by commas, got {item!r}")
        out[key.strip()] = value.strip()
    return out


def _read_header(lines, where):
    header, first, core_lines = {}, None, {}
    for i, line in enumerate(lines):
        stripped = line.strip()
        if not stripped:
            continue
        if not stripped.startswith("#"):
            first = i
            break
        key, sep, value = stripped.lstrip("#").partition(":")
        key = key.strip()
        if not sep or not key:
            continue  # a plain comment
        at = f"{where}, line {i + 1}, header key {key!r}"
        if key in _CORE_KEYS or key in _CORE_PLAIN:
            attr, x = _core_value(key, value, at)
            if attr in core_lines:
                raise ValueError(f"{at}: {attr!r} is already given on line {core_lines[attr]}; give it once")
            core_lines[attr] = i + 1
            header[attr] = x
        elif key in _FLOAT_KEYS:
            try:
                x = float(value)
            except ValueError:
                raise ValueError(f"{at}: {value.strip()!r} is not a number") from None
            if not math.isfinite(x) or (key in ("pore_volume_ml", "ooip_ml") and x <= 0.0):
                raise ValueError(f"{at}: {value.strip()!r} is out of range; allowed (0, inf)"
                                 if key in ("pore_volume_ml", "ooip_ml") else f"{at}: {x!r} must be finite")
            header[key] = x
        elif key in ("units", "columns"):
            header[key] = _pairs(value, at)
        else:
            header[key if key in _TEXT_KEYS else f"meta_{key}"] = value.strip()
    if first is None:
        raise ValueError(f"{where}: no column-name line (the file holds only header lines or is empty)")
    rate = header.get("qinj_ml_min")
    if isinstance(rate, tuple):
        if "core_diameter_m" not in header:
            raise ValueError(f"{where}, line {core_lines['qinj_ml_min']}, header key 'rate': a rate given as a "
                             f"velocity ({rate[1]}) needs the core diameter in the header (core_diameter)")
        header["qinj_ml_min"] = velocity_to_rate(rate[0], rate[1], header["core_diameter_m"])
    return header, first


def _mapping(names, explicit, header_map, where):
    mapping = {name: name for name in names}
    for source, given in (("header 'columns'", header_map), ("argument columns=", explicit)):
        for file_col, target in (given or {}).items():
            if file_col not in names:
                raise ValueError(f"{where}: {source} maps column {file_col!r}, which is not in the file; "
                                 f"file columns: {names}")
            if target is not None and target not in _COLUMNS:
                raise ValueError(f"{where}: {source} maps {file_col!r} to unknown column {target!r}; allowed "
                                 f"{list(_COLUMNS)} (or None to ignore it)")
            mapping[file_col] = target
    seen = {}
    for file_col, target in mapping.items():
        if target is None:
            continue
        if target not in _COLUMNS:
            raise ValueError(f"{where}: unknown column {file_col!r}; allowed columns {list(_COLUMNS)} (map others "
                             "with columns= or the 'columns' header, or to None to ignore them)")
        if target in seen:
            raise ValueError(f"{where}: columns {seen[target]!r} and {file_col!r} both map to {target!r}")
        seen[target] = file_col
    return seen  # spflow column -> file column


def _cell(text, line, file_col, where):
    text = text.strip()
    if text == "":
        return None
    try:
        x = float(text)
    except ValueError:
        raise ValueError(f"{where}, line {line}, column {file_col!r}: {text!r} is not a number") from None
    if math.isnan(x):
        raise ValueError(f"{where}, line {line}, column {file_col!r}: NaN (leave the cell empty if the quantity "
                         "was not measured at this PV)")
    if not math.isfinite(x):
        raise ValueError(f"{where}, line {line}, column {file_col!r}: {text!r} is not finite")
    return x


def _check_range(x, column, line, file_col, unit, where):
    lo, hi = (0.0, MAX_PV) if column == "pv" else VARIABLES[column][3]
    if not lo <= x <= hi:
        label = {"oil_volume": "negative volume", "dp": "negative dp"}.get(column, "out of range")
        if column == "pv":
            label = "negative PV" if x < lo else "absurd PV"
        target = "PV" if column == "pv" else VARIABLES[column][1]
        raise ValueError(f"{where}, line {line}, column {file_col!r}: {label}: {x!r} {target} (converted from unit "
                         f"{unit!r}) is outside the allowed range [{lo:g}, {hi:g}] {target}")


def read_csv(path, *, units=None, columns=None) -> tuple[xr.Dataset, str | None]:
    """The coreflood Dataset of the CSV file ``path`` and the header's ``schedule`` value (or ``None``)."""
    path = Path(path)
    where = f"file {str(path)!r}"
    if not path.is_file():
        raise ValueError(f"{where}: no such file")
    lines = read_utf8_text(path, where, "UTF-8 CSV text",
                           "expected a CSV coreflood (header lines, column names, rows)").splitlines()
    header, first = _read_header(lines, where)
    reader = csv.reader(lines[first:])
    names = [n.strip() for n in next(reader)]
    cols = _mapping(names, columns, header.get("columns"), where)
    if "pv" not in cols:
        raise ValueError(f"{where}: missing column 'pv' (injected pore volumes); file columns: {names}")
    if len(cols) == 1:
        raise ValueError(f"{where}: missing columns: no measured quantity; need at least one of "
                         f"{[c for c in _COLUMNS if c != 'pv']}")
    unit_of = {}
    for source, given in (("header 'units'", header.get("units")), ("argument units=", units)):
        for column, unit in (given or {}).items():
            if column not in _COLUMNS:
                raise ValueError(f"{where}: {source} names unknown column {column!r}; allowed {list(_COLUMNS)}")
            unit_of[column] = unit
    scale = {c: factor(c, unit_of.get(c, DEFAULT_UNITS[c]), f"{where}, column {cols[c]!r}") for c in cols}

    index = {c: names.index(f) for c, f in cols.items()}
    rows = []  # (line, {column: value or None})
    for offset, record in enumerate(reader):
        line = first + 2 + offset
        if not any(field.strip() for field in record):
            continue
        if len(record) != len(names):
            raise ValueError(f"{where}, line {line}: {len(record)} fields, expected {len(names)} ({names})")
        values = {}
        for c, i in index.items():
            x = _cell(record[i], line, cols[c], where)
            if x is not None:
                x *= scale[c]
                _check_range(x, c, line, cols[c], unit_of.get(c, DEFAULT_UNITS[c]), where)
            values[c] = x
        if values["pv"] is None:
            raise ValueError(f"{where}, line {line}, column {cols['pv']!r}: missing PV (every row needs one)")
        if rows and values["pv"] <= rows[-1][1]["pv"]:
            raise ValueError(f"{where}, line {line}, column {cols['pv']!r}: non-monotonic PV: {values['pv']!r} "
                             f"after {rows[-1][1]['pv']!r}; PV must increase strictly from row to row")
        rows.append((line, values))
    if not rows:
        raise ValueError(f"{where}: no data rows")

    pv_dp = [(v["pv"], v["dp"]) for _, v in rows if v.get("dp") is not None]
    tube_cols = [c for c in TUBE_VARIABLES if c in cols]
    tube_rows = [(line, v) for line, v in rows if any(v[c] is not None for c in tube_cols)]
    for line, v in tube_rows:
        for c in tube_cols:
            if c in _VOLUME_KEYS and v[c] is None:
                raise ValueError(f"{where}, line {line}, column {cols[c]!r}: missing value in a tube row (a tube "
                                 f"row needs every one of {[k for k in _VOLUME_KEYS if k in cols]})")
    tubes = {c: np.array([np.nan if v[c] is None else v[c] for _, v in tube_rows]) for c in tube_cols}
    if "recovery" in tubes:
        down = np.flatnonzero(np.diff(tubes["recovery"]) < 0.0)
        if down.size:
            line, k = tube_rows[down[0] + 1][0], down[0] + 1
            raise ValueError(f"{where}, line {line}, column {cols['recovery']!r}: decreasing recovery: "
                             f"{tubes['recovery'][k]!r} after {tubes['recovery'][k - 1]!r}; cumulative recovery must "
                             "not decrease (allowed: >= the previous tube's, within [0, 1])")
    end = np.array([v["pv"] for _, v in tube_rows])
    start = np.concatenate(([0.0], end[:-1]))
    _derive(tubes, start, end, header, [line for line, _ in tube_rows], where)

    attrs = {k: v for k, v in header.items() if k not in ("units", "columns", "schedule", "experiment", "source")}
    midpoints = _looks_like_midpoints(end - start)
    if midpoints:
        attrs[TUBE_ROWS_NOTE] = (f"{where}, line {tube_rows[0][0]}: {midpoints}; rows are read as tube ends "
                                 "(docs/data.md): if the PVs are tube midpoints, every tube is shifted by half a tube")
        warnings.warn(attrs[TUBE_ROWS_NOTE], UserWarning, stacklevel=3)
    ds = build_coreflood(experiment=header.get("experiment", path.stem), source=header.get("source", str(path)),
                         pv=[p for p, _ in pv_dp], dp=[d for _, d in pv_dp] if pv_dp else None,
                         tube_start=start, tube_end=end, tubes=tubes if tube_rows else None, attrs=attrs)
    return ds, header.get("schedule")


def _looks_like_midpoints(widths: np.ndarray) -> str:
    """A description of the pattern tube midpoints give when read as tube ends -- equal tubes after a first one of
    half their size -- or ``""``."""
    if widths.size < 3:
        return ""
    rest = widths[1:]
    typical = float(np.median(rest))
    if typical <= 0.0 or rest.max() > 1.1 * rest.min() or abs(widths[0] - 0.5 * typical) > 0.05 * typical:
        return ""
    return (f"the first tube (0, {widths[0]:.6g}] PV is half the size of the other {rest.size} "
            f"({typical:.6g} PV)")


def _derive(tubes, start, end, header, lines, where):
    """oil_cut and recovery from oil_volume where the header gives the pore volume / OOIP (in place)."""
    if "oil_volume" not in tubes:
        return
    oil = tubes["oil_volume"]
    if "oil_cut" not in tubes and "pore_volume_ml" in header:
        cut = oil / ((end - start) * header["pore_volume_ml"])
        bad = np.flatnonzero(cut > 1.0)
        if bad.size:
            raise ValueError(f"{where}, line {lines[bad[0]]}: oil_volume {oil[bad[0]]!r} ml exceeds the tube volume "
                             f"{(end - start)[bad[0]] * header['pore_volume_ml']!r} ml (oil cut would be > 1)")
        tubes["oil_cut"] = cut
    if "recovery" not in tubes and "ooip_ml" in header:
        tubes["recovery"] = np.cumsum(oil) / header["ooip_ml"]
