"""One number check for the forward model's call arguments and schedule fields: finite, inside a stated range, and
an error naming the field and the allowed range otherwise."""

from __future__ import annotations

import math

from spflow.core.errors import ParameterError

__all__ = ["check_number"]


def check_number(name: str, value, lower: float, upper: float, *, lower_open: bool = False) -> float:
    """``float(value)`` if it is a finite number (not a string) in ``(lower, upper]`` (``[lower, upper]`` unless
    ``lower_open``)."""
    rng = f"{'(' if lower_open else '['}{lower:g}, {upper:g}{')' if math.isinf(upper) else ']'}"
    if isinstance(value, (bool, str, bytes)):  # strings are not coerced
        raise ParameterError(f"{name} must be a number in {rng}, got {value!r}")
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise ParameterError(f"{name} must be a number in {rng}, got {value!r}") from None
    if not math.isfinite(x):
        raise ParameterError(f"{name} = {value!r} must be finite; allowed {rng}")
    if (x <= lower if lower_open else x < lower) or x > upper:
        raise ParameterError(f"{name} = {value!r} is out of range; allowed {rng}")
    return x
