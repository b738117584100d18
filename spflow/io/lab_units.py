"""Units accepted in users' coreflood files and their factors to the format's units (:mod:`spflow.io.format`)."""

from __future__ import annotations

__all__ = ["ALLOWED_UNITS", "DEFAULT_UNITS", "factor"]

_FRACTION = {"1": 1.0, "-": 1.0, "fraction": 1.0, "%": 0.01}
_PPM = {"ppm": 1.0, "mg/l": 1.0, "wt%": 1.0e4}

#: column -> {unit: factor to the format unit}
ALLOWED_UNITS: dict[str, dict[str, float]] = {
    "pv": {"PV": 1.0},
    "dp": {"Pa": 1.0, "kPa": 1.0e3, "MPa": 1.0e6, "mbar": 100.0, "bar": 1.0e5, "psi": 6894.757293168361},
    "oil_cut": _FRACTION,
    "recovery": _FRACTION,
    "oil_volume": {"ml": 1.0, "cm3": 1.0, "l": 1.0e3},
    "c_polymer_out": _PPM,
    "c_surfactant_out": _PPM,
    "salinity_out": _PPM,
}

#: column -> unit assumed when none is given
DEFAULT_UNITS = {"pv": "PV", "dp": "Pa", "oil_cut": "1", "recovery": "1", "oil_volume": "ml",
                 "c_polymer_out": "ppm", "c_surfactant_out": "ppm", "salinity_out": "ppm"}


def factor(column: str, unit: str, where: str) -> float:
    """Factor converting ``column`` from ``unit`` to the format unit; ``ValueError`` naming ``where`` otherwise."""
    allowed = ALLOWED_UNITS[column]
    if unit not in allowed:
        raise ValueError(f"{where}: unknown unit {unit!r} for column {column!r}; allowed units: "
                         f"{', '.join(allowed)}")
    return allowed[unit]
