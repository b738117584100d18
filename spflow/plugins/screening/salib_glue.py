"""What the Sobol' and Morris wrappers share around SALib: the ``problem`` dict, the design under the inputs'
marginals and the constant-QoI test.

A design under marginals (a space that records them: the ``priors`` stage's truncated normals, or beta laws) is drawn
as SALib draws it on the unit hypercube [0, 1]^d and mapped column by column through each marginal's quantile function
(:func:`~spflow.plugins.surrogates.input_marginals.from_unit_hypercube`, the isoprobabilistic transform). The
estimators only see the model outputs (Sobol') or the direction of each one-at-a-time step (Morris), so they then
estimate the measures under the marginals. For a uniform marginal the quantile function is SALib's own scaling
u (upper − lower) + lower, so a space of uniform marginals gives the box's design to the last bit.

A QoI that does not vary over a design (e.g. recovery at 0 PV, or a QoI no screened parameter reaches) has zero
variance and undefined sensitivity measures; SALib would return NaN. The wrappers report 0 with zero-width
intervals instead: no input explains any of its (absent) variance. "Does not vary" means a spread below 1e-12 of the
QoI's magnitude, i.e. round-off of a deterministic simulator.
"""

from __future__ import annotations

import numpy as np

__all__ = ["salib_problem", "salib_design", "is_constant"]

_CONSTANT_RTOL = 1e-12


def salib_problem(names, lower, upper) -> dict:
    """SALib's problem definition for independent uniform inputs on ``lower``..``upper``."""
    return {"num_vars": len(names), "names": list(names), "bounds": np.column_stack([lower, upper]).tolist()}


def salib_design(sample, names, lower, upper, inputs=None) -> np.ndarray:
    """``sample(problem)`` (a SALib sampler bound to its options) on the box ``lower``..``upper``, or with the marginals
    ``inputs`` (one per name) on the unit hypercube mapped through their quantile functions (module docstring)."""
    if inputs is None:
        return sample(salib_problem(names, lower, upper))
    from spflow.plugins.surrogates.input_marginals import from_unit_hypercube

    d = len(names)
    return from_unit_hypercube(inputs, sample(salib_problem(names, np.zeros(d), np.ones(d))))


def is_constant(y: np.ndarray) -> np.ndarray:
    """Per column of ``y``: True when the spread is round-off of the column's magnitude (see module docstring)."""
    spread = np.ptp(y, axis=0)
    return spread <= _CONSTANT_RTOL * np.max(np.abs(y), axis=0)
