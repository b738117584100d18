"""What the Sobol' and Morris wrappers share around SALib: the ``problem`` dict and the constant-QoI test.

A QoI that does not vary over a design (e.g. recovery at 0 PV, or a QoI no screened parameter reaches) has zero
variance and undefined sensitivity measures; SALib would return NaN. The wrappers report 0 with zero-width
intervals instead: no input explains any of its (absent) variance. "Does not vary" means a spread below 1e-12 of the
QoI's magnitude, i.e. round-off of a deterministic simulator.
"""

from __future__ import annotations

import numpy as np

__all__ = ["salib_problem", "is_constant"]

_CONSTANT_RTOL = 1e-12


def salib_problem(names, lower, upper) -> dict:
    """SALib's problem definition for independent uniform inputs on ``lower``..``upper``."""
    return {"num_vars": len(names), "names": list(names), "bounds": np.column_stack([lower, upper]).tolist()}


def is_constant(y: np.ndarray) -> np.ndarray:
    """Per column of ``y``: True when the spread is round-off of the column's magnitude (see module docstring)."""
    spread = np.ptp(y, axis=0)
    return spread <= _CONSTANT_RTOL * np.max(np.abs(y), axis=0)
