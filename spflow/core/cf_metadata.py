"""CF metadata of the netCDF files spflow writes: units, long names, and the ``Conventions`` a file may claim.

The convention (docs/architecture.md, "Units and CF metadata"):

* every numeric variable (data variable or coordinate) carries either
  - ``units``: a UDUNITS-2 string, ``"1"`` when dimensionless (injected pore volumes, fractions, log densities,
    counts and scores are ``"1"``), or
  - units per element: no ``units`` attribute, and ``units_variable`` naming a string variable of the same Dataset
    along one of the variable's dimensions whose entries are the UDUNITS units of the slices — for a vector whose
    entries are different quantities (the parameter vector θ: exponents, a viscosity, a dispersivity; the noise
    levels σ_i of blocks in Pa and in 1). CF has no attribute for this (CF-1.10 §3.1 wants the unit on the
    variable), so a CF reader sees such a variable without units; a file holding one does not claim CF;
* string and boolean variables carry no units;
* every variable carries a ``long_name`` (CF-1.10 §3.2).

A file whose every variable follows the first form claims ``Conventions = "CF-1.10"`` (:data:`CONVENTIONS`): of CF
it uses the ``Conventions`` (§2.6.1), ``units`` (§3.1) and ``long_name`` (§3.2) attributes and coordinate variables
named as their dimension (§1.3); it sets no ``standard_name`` (optional in CF). :func:`udunits` translates the forward
model's catalogue notation (``"-"``, ``"cP"``, ...) into UDUNITS strings where the translation is exact.
"""

from __future__ import annotations

import re

__all__ = ["CONVENTIONS", "UNITS_VARIABLE", "udunits"]

#: The ``Conventions`` attribute of a file whose variables all carry UDUNITS ``units`` and a ``long_name``.
CONVENTIONS = "CF-1.10"
#: Attribute naming the string variable that holds a variable's units per element (instead of ``units``).
UNITS_VARIABLE = "units_variable"

#: Catalogue notations UDUNITS reads differently or not at all, with their exact UDUNITS equivalent. "PV" (injected
#: pore volumes, a volume ratio) would parse as petavolt and "nat" as nano technical atmospheres.
_NOTATION = {"-": "1", "": "1", "PV": "1", "fraction": "1", "nat": "1", "cP": "cpoise", "wt%": "percent",
             "1/wt%": "1/percent", "1/vol. frac.": "1"}
_LOG = re.compile(r"lg\(re 1(?: (?P<unit>.+))?\)")


def udunits(unit: str) -> str:
    """The UDUNITS-2 form of a unit written in the forward model's catalogue notation (``"-"`` -> ``"1"``,
    ``"cP"`` -> ``"cpoise"``, ``"lg(re 1 cP)"`` -> ``"lg(re 1 cpoise)"``); any other string is returned unchanged
    (a unit with no exact UDUNITS form, e.g. ``ml/meq``, stays as written and fails the units check)."""
    unit = str(unit).strip()
    match = _LOG.fullmatch(unit)
    if match:
        inner = udunits(match["unit"] or "1")
        return "lg(re 1)" if inner == "1" else f"lg(re 1 {inner})"
    return _NOTATION.get(unit, unit)
