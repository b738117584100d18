"""One calibrated number of a parameter space (:class:`CalibratedParameter`) and its validation
(:func:`calibrated_parameter`).

A calibrated parameter is a label, the forward-model (UTCHEM) parameters it sets -- one, or a group moved together
(the thesis's ``n_high`` is the high-trapping-number Corey exponent of every phase, ``E1C``/``E2C``/``E3C``) --, a
range in the forward model's units and a scale (``linear`` or ``log``). It is written as a study's or a base model's
``[parameters]`` entry::

    ALPHAV2 = [0.0, 3.0]                                              # label = the one UTCHEM name it sets
    n_high = { names = ["E1C", "E2C", "E3C"], range = [1.5, 3.0] }   # one value for several UTCHEM names
    CRK = { range = [0.01, 0.1], scale = "log" }

The ``parameter_space`` stage, the gap diagnosis's base model and the study loader all validate entries here.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

from spflow.core.errors import ParameterError
from spflow.plugins.forward.parameters import PARAMETERS

__all__ = ["CalibratedParameter", "SCALES", "calibrated_parameter"]

_SPECS = {p.name: p for p in PARAMETERS}
#: the scales a calibrated parameter may be sampled on
SCALES = ("linear", "log")
_FIELDS = ("names", "range", "scale")


@dataclass(frozen=True)
class CalibratedParameter:
    """One calibrated number: a label, the UTCHEM names it sets, its range, its scale and unit (the names' common
    unit, as ``spflow list params`` writes it)."""

    label: str
    names: tuple[str, ...]
    lower: float
    upper: float
    log: bool = False
    unit: str = ""

    @property
    def default(self) -> float:
        """The forward model's default of the first name it sets (the thesis's calibrated value)."""
        return _SPECS[self.names[0]].default


def _number(where: str, value) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise ParameterError(f"{where} must be a finite number, got {value!r}")
    return float(value)


def calibrated_parameter(label: str, spec, where: str) -> CalibratedParameter:
    """The validated :class:`CalibratedParameter` of the entry ``label = spec`` (``[low, high]`` or a table with
    ``names``, ``range``, ``scale``; module docstring). ``where`` starts every error message (e.g. ``"base model
    [parameters] 'n_high'"``); errors are :class:`~spflow.core.errors.ParameterError` naming the field and the
    allowed values."""
    if isinstance(spec, Mapping):
        unknown = sorted(set(spec) - set(_FIELDS))
        if unknown:
            raise ParameterError(f"{where}: unknown field(s) {unknown}; allowed {list(_FIELDS)}")
        names, rng, scale = spec.get("names", [label]), spec.get("range"), spec.get("scale", "linear")
    else:
        names, rng, scale = [label], spec, "linear"
    if isinstance(names, str) or not isinstance(names, (list, tuple)) or not names:
        raise ParameterError(f"{where}: 'names' must be a non-empty list of UTCHEM parameter names, got {names!r}")
    for name in names:
        if name not in _SPECS:
            raise ParameterError(f"{where}: unknown forward-model parameter {name!r} (see `spflow list params`)")
    if len(set(names)) != len(names):
        raise ParameterError(f"{where}: 'names' {list(names)} repeats a name")
    if not isinstance(rng, (list, tuple)) or len(rng) != 2:
        raise ParameterError(f"{where}: 'range' must be [lower, upper], got {rng!r}")
    lo, hi = _number(f"{where} range lower", rng[0]), _number(f"{where} range upper", rng[1])
    if not lo < hi:
        raise ParameterError(f"{where}: range [{lo:g}, {hi:g}] must have lower < upper")
    for name in names:
        s = _SPECS[name]
        if lo < s.lower or hi > s.upper:
            raise ParameterError(f"{where}: range [{lo:g}, {hi:g}] leaves the bounds of {name} "
                                 f"{s.describe_range()}")
    if scale not in SCALES:
        raise ParameterError(f"{where}: 'scale' must be one of {list(SCALES)}, got {scale!r}")
    if scale == "log" and lo <= 0.0:
        raise ParameterError(f"{where}: a log scale needs lower > 0, got range [{lo:g}, {hi:g}]")
    units = sorted({_SPECS[n].unit for n in names})
    if len(units) > 1:
        raise ParameterError(f"{where}: 'names' {list(names)} have different units {units}; one value can only set "
                             "parameters of one unit")
    return CalibratedParameter(str(label), tuple(names), lo, hi, scale == "log", units[0])
