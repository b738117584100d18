"""CF metadata of the netCDF files spflow writes: units, long names, and the ``Conventions`` a file may claim.

The convention (docs/architecture.md, "Units and CF metadata"):

* every numeric variable (data variable or coordinate) carries either
  - ``units``: a UDUNITS-2 string, ``"1"`` when dimensionless (injected pore volumes, fractions, log densities,
    counts and scores are ``"1"``), or
  - units per element: no ``units`` attribute, and ``units_variable`` naming a string variable of the same Dataset
    along one or more of the variable's dimensions whose entries are the UDUNITS units of the slices — for a vector
    whose entries are different quantities (the parameter vector θ: exponents, a viscosity, a dispersivity; the noise
    levels σ_i of blocks in Pa and in 1), or a matrix whose entries are products of two such units (the covariance
    of a lab fit's estimates: a units variable over both of its dims, :func:`product_unit`). CF has no attribute
    for this (CF-1.10 §3.1 wants the unit on the variable), so a CF reader sees such a variable without units; a
    file holding one does not claim CF;
* string and boolean variables carry no units;
* every variable carries a ``long_name`` (CF-1.10 §3.2).

A file whose every variable follows the first form claims ``Conventions = "CF-1.10"`` (:data:`CONVENTIONS`; the
executor stamps it on a node's result when :func:`claims_cf` holds, so a Dataset with units per element makes no
claim): of CF
it uses the ``Conventions`` (§2.6.1), ``units`` (§3.1) and ``long_name`` (§3.2) attributes and coordinate variables
named as their dimension (§1.3); it sets no ``standard_name`` (optional in CF). :func:`udunits` translates the forward
model's catalogue notation (``"-"``, ``"cP"``, ``"meq/ml"``, ``"M$"``, ...) into UDUNITS strings; every catalogue unit
has one, so every unit spflow writes parses. Two quantities UDUNITS has no unit for are written with a UDUNITS unit of
the same scale and an attribute saying what is counted (:func:`unit_notes`, added by :func:`note_units` to every
result the executor stores):

* milliequivalents: ``meq/ml`` is written ``mmol/ml`` with ``equivalents = "mmol of unit charge (meq)"`` (a
  milliequivalent is a millimole of unit charge); spflow writes ``mmol`` for nothing else;
* money: ``M$`` is written ``1e6`` (a scaled dimensionless unit: value x 1e6 = amount) with ``currency = "USD"``; a
  price in ``$/bbl`` is written ``1/bbl`` with the same attribute; spflow writes the number ``1e6`` as a unit for
  nothing else.
"""

from __future__ import annotations

import re

import numpy as np

__all__ = ["CONVENTIONS", "UNITS_VARIABLE", "CRK_UNIT", "GAMMAC_UNIT", "EQUIVALENTS", "CURRENCY", "udunits",
           "unit_notes", "note_units", "product_unit", "squared_unit", "claims_cf", "has_units_per_element"]

#: The ``Conventions`` attribute of a file whose variables all carry UDUNITS ``units`` and a ``long_name``.
CONVENTIONS = "CF-1.10"
#: Attribute naming the string variable that holds a variable's units per element (instead of ``units``).
UNITS_VARIABLE = "units_variable"

#: CRK's unit, darcy^(1/2) (wt%)^(1/3) (derived from Eq. 2.8 in docs/forward_model.md, "Units"), as UDUNITS writes a
#: unit with fractional powers: a scaled integer-power unit. darcy^(1/2) is a length (UDUNITS' darcy is
#: 9.869233e-13 m2, its square root 9.934401e-07 m) and (wt%)^(1/3) the number 0.01^(1/3) = 0.2154435, so
#: 1 darcy^(1/2) (wt%)^(1/3) = 2.1403019e-07 m.
CRK_UNIT = "2.1403019e-07 m"
#: GAMMAC's unit, day darcy^(1/2) / (ft s) (UTCHEM's in-situ shear rate: GAMMAC u / sqrt(k ...) in 1/s for a flux u
#: in ft/day and k in darcy), a number: 86400 x 9.934401e-07 m / 0.3048 m = 0.28160508.
GAMMAC_UNIT = "0.28160508"
#: What ``mmol`` counts in every unit spflow writes (milliequivalents: millimoles of unit charge).
EQUIVALENTS = "mmol of unit charge (meq)"
#: The currency of every amount of money spflow writes (``1e6``: million US dollars; ``1/bbl``: US dollars per barrel).
CURRENCY = "USD"

#: Catalogue notations UDUNITS reads differently or not at all, with their UDUNITS equivalent. "PV" (injected pore
#: volumes, a volume ratio) would parse as petavolt and "nat" as nano technical atmospheres; milliequivalents are
#: millimoles of unit charge (:data:`EQUIVALENTS`), million US dollars the scaled number 1e6 (:data:`CURRENCY`).
#: CRK's former label ``darcy^0.5*(wt%)^-1/3`` (its wt% exponent mis-signed; same number) is read as CRK's unit.
_NOTATION = {"-": "1", "": "1", "PV": "1", "fraction": "1", "vol. frac.": "1", "1/vol. frac.": "1", "nat": "1",
             "iterations": "1",
             "cP": "cpoise", "mD": "millidarcy", "wt%": "percent", "1/wt%": "1/percent", "(wt%)^-1": "1/percent",
             "(wt%)^-2": "1/percent^2", "(wt%)^-3": "1/percent^3", "log10(dyne/cm)": "lg(re 1 dyne/cm)",
             "meq/ml": "mmol/ml", "ml/meq": "ml/mmol", "(1/s)/(meq/ml)": "(1/s)/(mmol/ml)",
             "M$": "1e6", "$/bbl": "1/bbl",
             "darcy^(1/2)*(wt%)^(1/3)": CRK_UNIT, "darcy^0.5*(wt%)^-1/3": CRK_UNIT,
             "day*darcy^(1/2)/(ft*s)": GAMMAC_UNIT, "day*darcy^0.5/(ft*s)": GAMMAC_UNIT}
_EQUIVALENTS = re.compile(r"\b(?:mmol|meq)\b")
#: How a ``long_name`` names a notation of money.
_SPOKEN = {"M$": "M$: million US dollars", "$/bbl": "US dollars per barrel"}
_MONEY = re.compile(r"\$|(?<![\w.])1e6(?![\w.])")
_LOG = re.compile(r"lg\(re 1(?: (?P<unit>.+))?\)")


def udunits(unit: str) -> str:
    """The UDUNITS-2 form of a unit written in the forward model's catalogue notation (``"-"`` -> ``"1"``,
    ``"cP"`` -> ``"cpoise"``, ``"meq/ml"`` -> ``"mmol/ml"``, ``"M$"`` -> ``"1e6"``, ``"lg(re 1 cP)"`` ->
    ``"lg(re 1 cpoise)"``); any other string is returned unchanged. What UDUNITS cannot say (that the mmol are of unit
    charge, that 1e6 counts US dollars) is in :func:`unit_notes`."""
    unit = str(unit).strip()
    match = _LOG.fullmatch(unit)
    if match:
        inner = udunits(match["unit"] or "1")
        return "lg(re 1)" if inner == "1" else f"lg(re 1 {inner})"
    return _NOTATION.get(unit, unit)


def unit_notes(*units: str) -> dict[str, str]:
    """The attributes that say what a variable in ``units`` (catalogue notation or UDUNITS; several for a units
    variable's entries) counts where UDUNITS cannot: ``equivalents`` (:data:`EQUIVALENTS`) for a unit with ``mmol``
    or ``meq``, ``currency`` (:data:`CURRENCY`) for one with ``$`` or the factor ``1e6``; ``{}`` for others."""
    notes = {}
    for unit in map(str, units):
        if _EQUIVALENTS.search(unit):
            notes["equivalents"] = EQUIVALENTS
        if _MONEY.search(unit):
            notes["currency"] = CURRENCY
    return notes


def note_units(ds):
    """``ds`` as spflow writes it (a shallow copy; the executor applies this to every result it stores): each
    ``units`` attribute and each entry of a units variable in its UDUNITS form (:func:`udunits`: a lab table's
    ``wt%`` or ``meq/ml`` column is written ``percent`` or ``mmol/ml``), with :func:`unit_notes` added to the
    variable's attrs (a writer's own attribute wins). A ``long_name`` whose unit was a notation UDUNITS has no unit
    for gets the notation appended (``"effective salinity (meq/ml)"``, ``"NPV (M$: million US dollars)"``)."""
    ds = ds.copy(deep=False)
    holders = {var.attrs[UNITS_VARIABLE] for var in ds.variables.values() if UNITS_VARIABLE in var.attrs}
    for name, var in ds.variables.items():
        units = []
        unit = var.attrs.get("units")
        if isinstance(unit, str):
            written = udunits(unit)
            if written != unit and unit_notes(unit):
                var.attrs["long_name"] = f"{var.attrs.get('long_name', name)} ({_SPOKEN.get(unit.strip(), unit)})"
            var.attrs["units"] = written
            units.append(unit)
        if name in holders and var.dtype.kind in "UO":
            entries = np.asarray(var.values)
            var.values = np.vectorize(udunits, otypes=[str])(entries) if entries.size else entries
            units += [str(u) for u in np.unique(entries.ravel())]
        for key, value in unit_notes(*units).items():
            var.attrs.setdefault(key, value)
    return ds


def product_unit(a: str, b: str) -> str:
    """The UDUNITS unit of a product of quantities in units ``a`` and ``b`` (UDUNITS strings): ``"1"`` drops out,
    equal units give ``"(a)^2"``, others ``"(a)*(b)"`` (parenthesised, so ``"1/s"`` times ``"cpoise"`` stays
    ``"(1/s)*(cpoise)"``). A covariance of estimates in units ``a`` and ``b`` is in ``product_unit(a, b)``, a variance
    in ``squared_unit(a)``. Logarithmic units (``lg(re 1 ...)``) have no product in UDUNITS: the string is built
    anyway and the units check rejects it."""
    a, b = str(a).strip(), str(b).strip()
    if a == "1":
        return b
    if b == "1":
        return a
    return f"({a})^2" if a == b else f"({a})*({b})"


def squared_unit(unit: str) -> str:
    """The UDUNITS unit of the square of a quantity in ``unit`` (``"1"`` stays ``"1"``, ``"Pa"`` is ``"(Pa)^2"``)."""
    return product_unit(unit, unit)


def claims_cf(ds) -> bool:
    """Whether ``ds`` may claim :data:`CONVENTIONS`: every variable has a ``long_name``, every numeric one a
    ``units`` string not in the catalogue notation :func:`udunits` rewrites (no units per element). Whether each
    string parses is not decided here (spflow carries no units library at run time): the tests parse the units of
    every built-in stage's schema and written results with UDUNITS-2."""
    for var in ds.variables.values():
        if not str(var.attrs.get("long_name", "")).strip():
            return False
        if var.dtype.kind in "fiuc":
            unit = var.attrs.get("units")
            if not isinstance(unit, str) or udunits(unit) != unit.strip() or UNITS_VARIABLE in var.attrs:
                return False
    return True


def has_units_per_element(ds, name: str) -> bool:
    """Whether variable ``name`` of ``ds`` has units per element: no ``units``, and ``units_variable`` naming a
    string variable of ``ds`` along one or more of its dimensions (one: a unit per parameter; two: a unit per pair
    of parameters, as a covariance's). What the entries are is for a units library to judge."""
    var = ds.variables[name]
    holder = ds.variables.get(var.attrs.get(UNITS_VARIABLE))
    return ("units" not in var.attrs and holder is not None and holder.ndim >= 1 and holder.dtype.kind in "UO"
            and set(holder.dims) <= set(var.dims))
