"""The coreflood data format shared by the bundled datasets, the synthetic twin and loaded lab files.

Two grids, because a lab measures on two:

* ``pv`` — pressure-transducer sample points (injected PV at the pump); variable ``dp`` (Pa), a point value.
* ``pv_tube`` — effluent-tube midpoints (PV), with coordinates ``pv_tube_start`` and ``pv_tube_end``; variables
  ``oil_cut`` (-, oil volume / tube volume), ``recovery`` (-, cumulative oil / OOIP at ``pv_tube_end``),
  ``oil_volume`` (ml, the tube reading) and effluent assays ``c_polymer_out``, ``c_surfactant_out``,
  ``salinity_out`` (ppm, tube averages; NaN where a tube held no aqueous phase).

Any QoI may be absent (partial data); attrs ``measured`` and ``missing`` list the QoIs (``dp``, ``oil_cut``,
``recovery``) present and absent. Required attrs: ``experiment``, ``source``; optional: ``schedule`` (JSON text
``{"name": ..., "slugs": [...]}``), ``generator``, ``seed``, ``spflow_version``, ``pore_volume_ml``, ``ooip_ml``,
core data with units (``core_length_m`` + ``core_length_m_units`` ..., :mod:`spflow.io.metadata`), ``noise_*``
(measurement model, see :class:`spflow.synthetic.NoiseModel`). Physically impossible data are rejected: a negative
``dp``, a decreasing ``recovery``, a PV outside ``[0, MAX_PV]``.
"""

from __future__ import annotations

import json

import numpy as np
import xarray as xr

from spflow.plugins.forward.schedule import as_schedule

__all__ = ["QOIS", "VARIABLES", "TUBE_VARIABLES", "MAX_PV", "schedule_json", "build_coreflood", "check_coreflood"]

#: the quantities of interest a calibration fits
QOIS = ("dp", "oil_cut", "recovery")

#: variable -> (dim, units, long name, allowed [low, high])
VARIABLES = {
    "dp": ("pv", "Pa", "pressure drop across the core (transducer reading)", (0.0, np.inf)),
    "oil_cut": ("pv_tube", "1", "oil volume fraction of the tube", (0.0, 1.0)),
    "recovery": ("pv_tube", "1", "cumulative oil recovery at pv_tube_end, fraction of OOIP", (0.0, 1.0)),
    "oil_volume": ("pv_tube", "ml", "oil volume read in the tube", (0.0, np.inf)),
    "c_polymer_out": ("pv_tube", "ppm", "polymer concentration of the tube's aqueous phase", (0.0, np.inf)),
    "c_surfactant_out": ("pv_tube", "ppm", "surfactant concentration of the tube (overall)", (0.0, np.inf)),
    "salinity_out": ("pv_tube", "ppm", "salinity (TDS) of the tube's aqueous phase", (0.0, np.inf)),
}
TUBE_VARIABLES = tuple(name for name, spec in VARIABLES.items() if spec[0] == "pv_tube")
#: the largest injected PV a coreflood may report (more is a unit or column mix-up, not a coreflood)
MAX_PV = 1.0e3
_NAN_ALLOWED = ("c_polymer_out", "c_surfactant_out", "salinity_out")


def schedule_json(schedule) -> str:
    """JSON text ``{"name", "slugs": [...]}`` of a schedule (anything :func:`as_schedule` accepts); a slug's
    ``rate_ml_min`` (ml/min) is written only when the slug sets its own rate (unset: the run's QINJ)."""
    sched = as_schedule(schedule)
    slugs = [{"name": s.name, "pv": s.pv, "salinity_ppm": s.salinity_ppm, "surfactant_ppm": s.surfactant_ppm,
              "polymer_ppm": s.polymer_ppm} | ({} if s.rate_ml_min is None else {"rate_ml_min": s.rate_ml_min})
             for s in sched.slugs]
    return json.dumps({"name": sched.name, "slugs": slugs})


def build_coreflood(*, experiment: str, source: str, pv=None, dp=None, tube_start=None, tube_end=None,
                    tubes=None, attrs=None) -> xr.Dataset:
    """Assemble a coreflood Dataset in the format above (arrays already in format units).

    ``pv``/``dp`` give the pressure series (or ``None``); ``tube_start``/``tube_end`` (PV) and ``tubes``
    (``{name: array}`` for names in ``TUBE_VARIABLES``) give the tube data (or ``None``).
    """
    data, coords = {}, {}
    if dp is not None:
        coords["pv"] = ("pv", np.asarray(pv, dtype=np.float64), {"units": "PV",
                                                                  "long_name": "injected PV at the sample"})
        data["dp"] = ("pv", np.asarray(dp, dtype=np.float64))
    if tubes:
        start = np.asarray(tube_start, dtype=np.float64)
        end = np.asarray(tube_end, dtype=np.float64)
        coords["pv_tube"] = ("pv_tube", 0.5 * (start + end), {"units": "PV", "long_name": "tube midpoint"})
        coords["pv_tube_start"] = ("pv_tube", start, {"units": "PV", "long_name": "injected PV at tube start"})
        coords["pv_tube_end"] = ("pv_tube", end, {"units": "PV", "long_name": "injected PV at tube end"})
        for name, values in tubes.items():
            if name not in TUBE_VARIABLES:
                raise ValueError(f"unknown tube variable {name!r}; allowed {list(TUBE_VARIABLES)}")
            data[name] = ("pv_tube", np.asarray(values, dtype=np.float64))
    ds = xr.Dataset(data, coords=coords)
    for name in ds.data_vars:
        ds[name].attrs.update(units=VARIABLES[name][1], long_name=VARIABLES[name][2])
    ds.attrs.update(attrs or {})
    ds.attrs.update(experiment=str(experiment), source=str(source),
                    measured=" ".join(q for q in QOIS if q in ds), missing=" ".join(q for q in QOIS if q not in ds))
    return ds


def _fail(source: str, message: str):
    raise ValueError(f"{source}: {message}")


def check_coreflood(ds: xr.Dataset, source: str) -> xr.Dataset:
    """Validate a Dataset claimed to be in the coreflood format; ``ValueError`` naming ``source``, the variable
    and the index at fault. Returns ``ds`` unchanged."""
    unknown = sorted(set(ds.data_vars) - set(VARIABLES))
    if unknown:
        _fail(source, f"unknown variable(s) {unknown}; allowed {list(VARIABLES)}")
    if not any(q in ds for q in QOIS):
        _fail(source, f"missing variables: none of {list(QOIS)} is present")
    for attr in ("experiment", "source"):
        if attr not in ds.attrs:
            _fail(source, f"missing attribute {attr!r}")
    for coord in ("pv", "pv_tube", "pv_tube_start", "pv_tube_end"):
        if coord in ds.coords:
            x = ds[coord].values
            if ds[coord].attrs.get("units") != "PV":
                _fail(source, f"coordinate {coord!r} has units {ds[coord].attrs.get('units')!r}; expected 'PV'")
            bad = np.flatnonzero(~np.isfinite(x) | (x < 0.0) | (x > MAX_PV))
            if bad.size:
                _fail(source, f"coordinate {coord!r} index {bad[0]}: {float(x[bad[0]])!r} is not a PV in "
                      f"[0, {MAX_PV:g}]")
            steps = np.flatnonzero(np.diff(x) <= 0.0)
            if steps.size:
                i = steps[0] + 1
                _fail(source, f"coordinate {coord!r} is not increasing at index {i}: {float(x[i])!r} after "
                      f"{float(x[i - 1])!r}")
    for name, da in ds.data_vars.items():
        dim, unit, _, (lo, hi) = VARIABLES[name]
        if da.dims != (dim,):
            _fail(source, f"variable {name!r} has dims {da.dims}; expected ({dim!r},)")
        if da.attrs.get("units") != unit:
            _fail(source, f"variable {name!r} has units {da.attrs.get('units')!r}; expected {unit!r}")
        x = da.values
        nan = np.isnan(x)
        if nan.any() and name not in _NAN_ALLOWED:
            _fail(source, f"variable {name!r} index {np.flatnonzero(nan)[0]} is NaN")
        bad = np.flatnonzero(~nan & ((x < lo) | (x > hi)))
        if bad.size:
            _fail(source, f"variable {name!r} index {bad[0]} = {float(x[bad[0]])!r} is outside [{lo:g}, {hi:g}] "
                  f"(units {unit!r})")
    if "recovery" in ds:
        x = ds["recovery"].values
        down = np.flatnonzero(np.diff(x) < 0.0)
        if down.size:
            i = down[0] + 1
            _fail(source, f"variable 'recovery' decreases at index {i}: {float(x[i])!r} after {float(x[i - 1])!r}; "
                  "cumulative recovery must not decrease (allowed: recovery[i] >= recovery[i-1], within [0, 1])")
    return ds
