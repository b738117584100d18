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
model's catalogue notation (``"-"``, ``"cP"``, ...) into UDUNITS strings where the translation is exact.
"""

from __future__ import annotations

import re

__all__ = ["CONVENTIONS", "UNITS_VARIABLE", "NO_UDUNITS_FORM", "udunits", "product_unit", "squared_unit",
           "claims_cf", "has_units_per_element"]

#: The ``Conventions`` attribute of a file whose variables all carry UDUNITS ``units`` and a ``long_name``.
CONVENTIONS = "CF-1.10"
#: Attribute naming the string variable that holds a variable's units per element (instead of ``units``).
UNITS_VARIABLE = "units_variable"

#: Catalogue notations UDUNITS reads differently or not at all, with their exact UDUNITS equivalent. "PV" (injected
#: pore volumes, a volume ratio) would parse as petavolt and "nat" as nano technical atmospheres.
_NOTATION = {"-": "1", "": "1", "PV": "1", "fraction": "1", "vol. frac.": "1", "1/vol. frac.": "1", "nat": "1",
             "cP": "cpoise", "mD": "millidarcy", "wt%": "percent", "1/wt%": "1/percent", "(wt%)^-1": "1/percent",
             "(wt%)^-2": "1/percent^2", "(wt%)^-3": "1/percent^3", "log10(dyne/cm)": "lg(re 1 dyne/cm)"}
#: Units of the forward model's catalogue that have no exact UDUNITS form: milliequivalents are not a UDUNITS unit,
#: and UDUNITS takes no fractional powers. A Dataset holding one claims no CF conventions (:func:`claims_cf`).
NO_UDUNITS_FORM = frozenset({"meq/ml", "ml/meq", "(1/s)/(meq/ml)", "darcy^0.5*(wt%)^-1/3"})
_LOG = re.compile(r"lg\(re 1(?: (?P<unit>.+))?\)")


def udunits(unit: str) -> str:
    """The UDUNITS-2 form of a unit written in the forward model's catalogue notation (``"-"`` -> ``"1"``,
    ``"cP"`` -> ``"cpoise"``, ``"lg(re 1 cP)"`` -> ``"lg(re 1 cpoise)"``); any other string is returned unchanged
    (a unit with no exact UDUNITS form stays as written and fails the units check: milliequivalents, ``meq/ml``,
    are not a UDUNITS unit, and ``darcy^0.5*(wt%)^-1/3`` has fractional powers UDUNITS does not take)."""
    unit = str(unit).strip()
    match = _LOG.fullmatch(unit)
    if match:
        inner = udunits(match["unit"] or "1")
        return "lg(re 1)" if inner == "1" else f"lg(re 1 {inner})"
    return _NOTATION.get(unit, unit)


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
    ``units`` string not in the catalogue notation :func:`udunits` rewrites nor in :data:`NO_UDUNITS_FORM` (no units
    per element). Whether each
    string parses is not decided here (spflow carries no units library at run time): the tests parse the units of
    every built-in stage's schema and written results with UDUNITS-2."""
    for var in ds.variables.values():
        if not str(var.attrs.get("long_name", "")).strip():
            return False
        if var.dtype.kind in "fiuc":
            unit = var.attrs.get("units")
            if (not isinstance(unit, str) or udunits(unit) != unit.strip() or unit.strip() in NO_UDUNITS_FORM
                    or UNITS_VARIABLE in var.attrs):
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
