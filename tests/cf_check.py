"""The units / long_name check of docs/architecture.md ("Units and CF metadata"), with a units library (cf-units, which
bundles UDUNITS-2) as the judge of what a unit string means.

A numeric variable passes with a ``units`` string UDUNITS parses — except strings UDUNITS reads as something else than
spflow meant (``PV`` is petavolt, ``nat`` nano technical atmospheres, ``-`` no unit at all) — or, when
``per_element`` is allowed, with no ``units`` but ``units_variable`` naming a string variable along one or more of its
dims (a covariance's: both) whose every entry passes the same test. String and boolean variables need no units.
Every variable needs a non-empty ``long_name`` when ``long_names`` is asked for.
"""

from __future__ import annotations

import cf_units
import numpy as np
import xarray as xr

#: Unit strings UDUNITS parses into a different quantity than meant (or into nothing).
MISREAD = {"PV": "petavolt", "nat": "nano technical atmosphere", "-": "no unit", "": "no unit"}


def unit_problem(unit) -> str | None:
    """Why ``unit`` is not an acceptable UDUNITS string, or None."""
    if not isinstance(unit, str):
        return f"units {unit!r} is not a string"
    unit = str(unit)  # a numpy string as plain text
    if unit.strip() in MISREAD:
        return f"units {unit!r} reads as {MISREAD[unit.strip()]} in UDUNITS"
    try:
        cf_units.Unit(unit)
    except ValueError:
        return f"units {unit!r} is not a UDUNITS unit"
    return None


def variable_problems(ds: xr.Dataset, name: str, *, per_element: bool = True, long_names: bool = True) -> list[str]:
    var = ds.variables[name]
    problems = []
    if long_names and not str(var.attrs.get("long_name", "")).strip():
        problems.append(f"{name}: no long_name")
    if var.dtype.kind in "UOSb":
        return problems
    if "units" in var.attrs:
        if "units_variable" in var.attrs:
            problems.append(f"{name}: both units and units_variable")
        why = unit_problem(var.attrs["units"])
        return problems + ([f"{name}: {why}"] if why else [])
    holder = var.attrs.get("units_variable")
    if holder is None or not per_element:
        return problems + [f"{name}: no units"]
    units = ds.variables.get(holder)
    if units is None or units.ndim < 1 or not set(units.dims) <= set(var.dims) or units.dtype.kind not in "UO":
        return problems + [f"{name}: units_variable {holder!r} is not a string variable along some of {var.dims}"]
    return problems + [f"{name}: entry of {holder}: {why}"
                       for why in map(unit_problem, np.asarray(units.values).ravel()) if why]


def dataset_problems(ds: xr.Dataset, **kwargs) -> list[str]:
    """Every variable's problems (data variables and coordinates)."""
    return [p for name in ds.variables for p in variable_problems(ds, str(name), **kwargs)]
