"""Values with units, as a user writes them (``"0.30 m"``, ``"1.5 in"``, ``"500 mD"``, ``"0.5 ml/min"``, ``"19 %"``),
converted to the forward model's units.

A quantity is written either as a string ``"<number> <unit>"`` or as a table ``{value = 0.3, units = "m"}``; a
bare number is accepted only for dimensionless kinds (a fraction). Each *kind* has one target unit (the forward
model's, :mod:`spflow.plugins.forward.parameters`) and a table of accepted units with their factors to it.
Injection rates may also be given as a superficial (Darcy) velocity ``q / A`` (``ft/day``, ``m/day``, ``cm/min``);
converting one needs the core's cross-section, see :func:`velocity_to_rate`.
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping

from spflow.core.errors import ParameterError

__all__ = ["KINDS", "VELOCITY_UNITS", "parse_quantity", "velocity_to_rate"]

_INCH = 0.0254
_FOOT = 0.3048

#: kind -> (target unit, {accepted unit: factor to the target unit})
KINDS: dict[str, tuple[str, dict[str, float]]] = {
    "length": ("m", {"m": 1.0, "cm": 1.0e-2, "mm": 1.0e-3, "in": _INCH, "ft": _FOOT}),
    "fraction": ("1", {"1": 1.0, "fraction": 1.0, "-": 1.0, "%": 1.0e-2}),
    "permeability": ("mD", {"mD": 1.0, "md": 1.0, "D": 1.0e3, "darcy": 1.0e3}),
    "rate": ("ml/min", {"ml/min": 1.0, "cm3/min": 1.0, "cc/min": 1.0, "ml/h": 1.0 / 60.0, "ml/s": 60.0,
                        "l/min": 1.0e3}),
    "viscosity": ("cP", {"cP": 1.0, "mPa.s": 1.0, "mPa s": 1.0, "Pa.s": 1.0e3}),
    "ion_concentration": ("meq/ml", {"meq/ml": 1.0, "eq/l": 1.0, "meq/l": 1.0e-3}),
}

#: superficial-velocity units accepted for a rate -> factor to m/s
VELOCITY_UNITS: dict[str, float] = {"ft/day": _FOOT / 86400.0, "m/day": 1.0 / 86400.0, "cm/min": 1.0e-2 / 60.0}

_NUMBER_UNIT = re.compile(r"^\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*(.*?)\s*$")


def _allowed(kind: str) -> list[str]:
    units = list(KINDS[kind][1])
    return units + list(VELOCITY_UNITS) if kind == "rate" else units


def parse_quantity(value, kind: str, where: str) -> tuple[float, str]:
    """``(number in the kind's target unit, unit as written)`` of ``value``; for a rate given as a velocity the
    number is in that velocity unit and the caller converts it with :func:`velocity_to_rate`.

    Raises :class:`ParameterError` naming ``where``, what was given and the accepted units.
    """
    target, table = KINDS[kind]
    allowed = ", ".join(_allowed(kind))
    if isinstance(value, Mapping):
        unknown = sorted(set(value) - {"value", "units"})
        if unknown or "value" not in value or "units" not in value:
            raise ParameterError(f"{where}: a quantity table needs exactly the keys ['value', 'units'], got "
                                 f"{sorted(value)}")
        number, unit = value["value"], value["units"]
        if isinstance(number, bool) or not isinstance(number, (int, float)):
            raise ParameterError(f"{where}: 'value' must be a number, got {number!r}")
        if not isinstance(unit, str):
            raise ParameterError(f"{where}: 'units' must be a string; allowed units: {allowed}")
        number, unit = float(number), unit.strip()
    elif isinstance(value, bool):
        raise ParameterError(f"{where}: expected a number with units (e.g. \"1 {target}\"), got {value!r}")
    elif isinstance(value, (int, float)):
        if kind != "fraction":
            raise ParameterError(f"{where}: {value!r} has no units; write it as \"{value} <unit>\" with one of the "
                                 f"units: {allowed}")
        number, unit = float(value), "1"
    elif isinstance(value, str):
        match = _NUMBER_UNIT.match(value)
        if match is None:
            raise ParameterError(f"{where}: {value!r} is not '<number> <unit>'; allowed units: {allowed}")
        number, unit = float(match.group(1)), match.group(2)
        if not unit:
            if kind != "fraction":
                raise ParameterError(f"{where}: {value!r} has no units; allowed units: {allowed}")
            unit = "1"
    else:
        raise ParameterError(f"{where}: expected \"<number> <unit>\" or {{value = ..., units = \"...\"}}, got "
                             f"{type(value).__name__}")
    if not math.isfinite(number):
        raise ParameterError(f"{where}: {number!r} is not finite")
    if kind == "rate" and unit in VELOCITY_UNITS:
        return number, unit
    if unit not in table:
        raise ParameterError(f"{where}: unknown unit {unit!r}; allowed units: {allowed}")
    return number * table[unit], unit


def velocity_to_rate(velocity: float, unit: str, diameter_m: float) -> float:
    """The volumetric rate (ml/min) of superficial velocity ``velocity`` (``unit`` in :data:`VELOCITY_UNITS`)
    through a core of diameter ``diameter_m``: ``q = u * pi D^2 / 4``."""
    area_m2 = math.pi * diameter_m**2 / 4.0
    return velocity * VELOCITY_UNITS[unit] * area_m2 * 1.0e6 * 60.0
