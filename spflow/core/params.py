"""Typed, validated stage parameters.

A stage declares ``params = {"n": Param(int, 64, bounds=(1, None), doc="...")}``. Validation happens when the stage
is instantiated (so before any work), and errors name the stage, the parameter and the allowed range. The validated
parameters are plain JSON-compatible values, which makes them canonical for the provenance key.
"""

from __future__ import annotations

import difflib
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from .errors import ParameterError

__all__ = ["Param", "validate_params"]

_REQUIRED = object()


@dataclass(frozen=True)
class Param:
    """Declaration of one stage parameter.

    Parameters
    ----------
    kind:
        ``int``, ``float``, ``str``, ``bool``, ``list`` (a JSON-compatible list) or ``dict`` (JSON-compatible mapping).
    default:
        Default value; omit to make the parameter required.
    bounds:
        Inclusive ``(low, high)`` for numbers (``None`` = unbounded side); for lists, bounds on each number inside.
    choices:
        Allowed values for strings (or list items).
    doc:
        One line shown by ``spflow list``.
    unit:
        Unit label for numeric parameters.
    """

    kind: type
    default: Any = _REQUIRED
    bounds: tuple[float | None, float | None] | None = None
    choices: Sequence[Any] | None = None
    doc: str = ""
    unit: str = ""

    @property
    def required(self) -> bool:
        return self.default is _REQUIRED

    def describe_range(self) -> str:
        if self.choices is not None:
            return "one of " + ", ".join(repr(c) for c in self.choices)
        if self.bounds is not None:
            lo, hi = self.bounds
            lo_s = "-inf" if lo is None else repr(lo)
            hi_s = "inf" if hi is None else repr(hi)
            return f"[{lo_s}, {hi_s}]" + (f" {self.unit}" if self.unit else "")
        return f"any {self.kind.__name__}"


def _check_number(where: str, value: Any, spec: Param, kind: type) -> float | int:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        try:
            import numpy as np

            if isinstance(value, np.generic) and not isinstance(value, np.bool_):
                value = value.item()
            else:
                raise TypeError
        except TypeError:
            raise ParameterError(f"{where} must be a {kind.__name__}, got {type(value).__name__} {value!r}") from None
    if kind is int:
        if isinstance(value, float) and not value.is_integer():
            raise ParameterError(f"{where} must be an integer, got {value!r}")
        value = int(value)
    else:
        value = float(value)
        if not math.isfinite(value):
            raise ParameterError(f"{where} must be finite, got {value!r}; allowed range {spec.describe_range()}")
    if spec.bounds is not None:
        lo, hi = spec.bounds
        if (lo is not None and value < lo) or (hi is not None and value > hi):
            raise ParameterError(f"{where} = {value!r} is outside the allowed range {spec.describe_range()}")
    return value


def _check_value(where: str, value: Any, spec: Param) -> Any:
    kind = spec.kind
    if kind in (int, float):
        return _check_number(where, value, spec, kind)
    if kind is bool:
        if not isinstance(value, bool):
            raise ParameterError(f"{where} must be true or false, got {value!r}")
        return value
    if kind is str:
        if not isinstance(value, str):
            raise ParameterError(f"{where} must be a string, got {type(value).__name__} {value!r}")
        if spec.choices is not None and value not in spec.choices:
            raise ParameterError(f"{where} = {value!r} is not allowed; allowed: {spec.describe_range()}")
        return value
    if kind is list:
        if isinstance(value, (str, bytes)) or not isinstance(value, Sequence):
            raise ParameterError(f"{where} must be a list, got {type(value).__name__} {value!r}")
        out = []
        for i, item in enumerate(value):
            item_where = f"{where}[{i}]"
            if spec.choices is not None and item not in spec.choices:
                raise ParameterError(f"{item_where} = {item!r} is not allowed; allowed: {spec.describe_range()}")
            if isinstance(item, (int, float)) and not isinstance(item, bool):
                item = _check_number(item_where, item, spec, float if isinstance(item, float) else int)
            out.append(item)
        return out
    if kind is dict:
        if not isinstance(value, Mapping):
            raise ParameterError(f"{where} must be a mapping, got {type(value).__name__} {value!r}")
        return {str(k): value[k] for k in sorted(value)}
    raise ParameterError(f"{where}: unsupported parameter kind {kind!r}")


def validate_params(stage: str, specs: Mapping[str, Param], given: Mapping[str, Any] | None) -> dict[str, Any]:
    """Return the complete, validated parameter dict of ``stage`` (defaults filled in).

    Raises :class:`ParameterError` naming the stage and parameter for unknown names (with close matches), missing
    required parameters, wrong types and out-of-range values.
    """
    given = dict(given or {})
    unknown = sorted(set(given) - set(specs))
    if unknown:
        name = unknown[0]
        close = difflib.get_close_matches(name, list(specs), n=3)
        hint = f"; did you mean {', '.join(close)}?" if close else ""
        known = ", ".join(sorted(specs)) or "none"
        raise ParameterError(f"stage {stage!r} has no parameter {name!r}{hint} (known parameters: {known})")
    out: dict[str, Any] = {}
    for name in sorted(specs):
        spec = specs[name]
        where = f"stage {stage!r} parameter {name!r}"
        if name in given:
            out[name] = _check_value(where, given[name], spec)
        elif spec.required:
            raise ParameterError(f"{where} is required ({spec.describe_range()}): {spec.doc}")
        else:
            out[name] = spec.default
    return out
