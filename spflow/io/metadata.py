"""The metadata attrs of a coreflood Dataset: core data with units, volumes, schedule, measurement model.

Core data (``docs/data.md``): one attr per quantity, its unit in the name and, machine-readable, in a companion
``<attr>_units`` attr (UDUNITS-style string), in the forward model's units and inside the forward model's bounds:

======================  =========  ===================  ======================================
attr                    units      forward parameter    meaning
======================  =========  ===================  ======================================
``core_length_m``       m          ``LENGTH``           core length
``core_diameter_m``     m          ``DIAMETER``         core diameter
``porosity``            1          ``PORO``             porosity
``permeability_md``     mD         ``PERM``             absolute permeability
``swi``                 1          ``SWI``              initial water saturation
``qinj_ml_min``         ml/min     ``QINJ``             injection rate
======================  =========  ===================  ======================================

Volumes ``pore_volume_ml`` and ``ooip_ml`` (> 0), the ``schedule`` JSON text and the measurement model
``noise_<field>`` (:class:`spflow.synthetic.NoiseModel`) are validated by :func:`check_metadata` with errors naming
the file (``where``), the attr and the allowed range — the same rules for netCDF attrs and CSV header lines.
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping
from dataclasses import fields

from spflow.plugins.forward.parameters import PARAMETERS
from spflow.plugins.forward.schedule import as_schedule
from spflow.synthetic.noise_model import NoiseModel

__all__ = ["CORE_ATTRS", "VOLUME_ATTRS", "NOISE_ATTRS", "core_unit", "core_bounds", "check_metadata",
           "core_params"]

#: core attr -> forward-model parameter
CORE_ATTRS: dict[str, str] = {"core_length_m": "LENGTH", "core_diameter_m": "DIAMETER", "porosity": "PORO",
                              "permeability_md": "PERM", "swi": "SWI", "qinj_ml_min": "QINJ"}
#: volume attrs (ml, > 0)
VOLUME_ATTRS = ("pore_volume_ml", "ooip_ml")
#: measurement-model attr -> NoiseModel field
NOISE_ATTRS: dict[str, str] = {f"noise_{f.name}": f.name for f in fields(NoiseModel)}

_SPECS = {p.name: p for p in PARAMETERS}


def core_unit(attr: str) -> str:
    """The units string of core attr ``attr`` (the forward model's unit; ``"1"`` for a fraction)."""
    unit = _SPECS[CORE_ATTRS[attr]].unit
    return "1" if unit == "-" else unit


def core_bounds(attr: str) -> tuple[float, float]:
    """The allowed ``[lower, upper]`` of core attr ``attr`` (the forward model's bounds)."""
    spec = _SPECS[CORE_ATTRS[attr]]
    return spec.lower, spec.upper


def _number(value, where: str, attr: str, allowed: str) -> float:
    if isinstance(value, bool):
        raise ValueError(f"{where}: attr {attr!r} = {value!r} is not a number; allowed {allowed}")
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{where}: attr {attr!r} = {value!r} is not a number; allowed {allowed}") from None
    if not math.isfinite(x):
        raise ValueError(f"{where}: attr {attr!r} = {x!r} is not finite; allowed {allowed}")
    return x


def _check_units(attrs: Mapping, out: dict, attr: str, unit: str, where: str) -> None:
    key = f"{attr}_units"
    if key in attrs and str(attrs[key]) != unit:
        raise ValueError(f"{where}: attr {key!r} = {attrs[key]!r}; the format stores {attr!r} in {unit!r} only")
    out[key] = unit


def check_metadata(attrs: Mapping, where: str) -> dict:
    """A copy of ``attrs`` with every metadata attr validated and each core / noise attr's ``_units`` companion
    set. Raises ``ValueError`` naming ``where``, the attr, the value and the allowed range/values."""
    out = dict(attrs)
    for attr in CORE_ATTRS:
        if attr in attrs:
            lo, hi = core_bounds(attr)
            unit = core_unit(attr)
            allowed = f"[{lo:g}, {hi:g}] {unit}"
            x = _number(attrs[attr], where, attr, allowed)
            if not lo <= x <= hi:
                raise ValueError(f"{where}: attr {attr!r} = {x!r} {unit} is out of range; allowed {allowed}")
            out[attr] = x
            _check_units(attrs, out, attr, unit, where)
        elif f"{attr}_units" in attrs:
            raise ValueError(f"{where}: attr '{attr}_units' without the value attr {attr!r}")
    for attr in VOLUME_ATTRS:
        if attr in attrs:
            x = _number(attrs[attr], where, attr, "(0, inf) ml")
            if x <= 0.0:
                raise ValueError(f"{where}: attr {attr!r} = {x!r} ml is out of range; allowed (0, inf) ml")
            out[attr] = x
    noise = {}
    for attr, name in NOISE_ATTRS.items():
        if attr in attrs:
            noise[name] = _number(attrs[attr], where, attr, "a NoiseModel value (docs/data.md)")
            out[attr] = noise[name]
    if noise:
        try:
            NoiseModel(**noise)
        except ValueError as exc:
            raise ValueError(f"{where}: measurement-model attrs (noise_*): {exc}") from None
        units = NoiseModel().to_attrs()
        for name in noise:
            _check_units(attrs, out, f"noise_{name}", units[f"noise_{name}_units"], where)
    if "schedule" in attrs:
        out["schedule"] = _check_schedule(attrs["schedule"], where)
    return out


def _check_schedule(text, where: str) -> str:
    if not isinstance(text, str):
        raise ValueError(f"{where}: attr 'schedule' must be JSON text {{\"name\": ..., \"slugs\": [...]}}, got "
                         f"{type(text).__name__}")
    try:
        parsed = json.loads(text)
    except json.JSONDecodeError as exc:
        raise ValueError(f"{where}: attr 'schedule' is not valid JSON ({exc.msg} at character {exc.pos}); expected "
                         "{\"name\": ..., \"slugs\": [{\"pv\", \"salinity_ppm\", \"surfactant_ppm\", "
                         "\"polymer_ppm\", \"name\"}, ...]}") from None
    try:
        as_schedule(parsed)
    except ValueError as exc:
        raise ValueError(f"{where}: attr 'schedule': {exc}") from None
    return text


def core_params(attrs: Mapping) -> dict[str, float]:
    """The forward-model parameters (``LENGTH`` ...) of the core attrs present in ``attrs``."""
    return {param: float(attrs[attr]) for attr, param in CORE_ATTRS.items() if attr in attrs}
