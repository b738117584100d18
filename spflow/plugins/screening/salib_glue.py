"""What the Sobol' and Morris wrappers share around SALib: the ``problem`` dict, the design under the inputs'
marginals and the constant-QoI test.

A design under marginals (a space that records them: the ``priors`` stage's truncated normals, or beta laws) is drawn
as SALib draws it on the unit hypercube [0, 1]^d and mapped column by column through each marginal's quantile function
(:func:`~spflow.plugins.surrogates.input_marginals.from_unit_hypercube`, the isoprobabilistic transform). The
estimators only see the model outputs (Sobol') or the direction of each one-at-a-time step (Morris), so they then
estimate the measures under the marginals. For a uniform marginal the quantile function is SALib's own scaling
u (upper − lower) + lower, so a space of uniform marginals gives the box's design to the last bit. Where a marginal's
quantile function is infinite on a face of the cube (an unbounded law: normal, lognormal), a design point on that face
is moved half a cell of SALib's 30-bit Sobol' points (2^-31) inside, so every point is finite; other points and
bounded marginals are untouched.

A QoI that does not vary over a design (e.g. recovery at 0 PV, or a QoI no screened parameter reaches) has zero
variance and undefined sensitivity measures; SALib would return NaN. The wrappers report 0 with zero-width
intervals instead: no input explains any of its (absent) variance. "Does not vary" means a spread below 1e-12 of the
QoI's magnitude, i.e. round-off of a deterministic simulator.
"""

from __future__ import annotations

import numpy as np

__all__ = ["salib_problem", "salib_design", "is_constant"]

_CONSTANT_RTOL = 1e-12
#: Half a cell of the 30-bit Sobol' points SALib draws (scipy's default): how far a point on an infinite face moves.
_FACE_OFFSET = 0.5**31


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
    u = np.array(sample(salib_problem(names, np.zeros(d), np.ones(d))), dtype=float)
    for j, marginal in enumerate(inputs):
        low, high = np.isinf(marginal.ppf(np.array([0.0, 1.0])))
        if low:
            u[u[:, j] == 0.0, j] = _FACE_OFFSET
        if high:
            u[u[:, j] == 1.0, j] = 1.0 - _FACE_OFFSET
    return from_unit_hypercube(inputs, u)


def is_constant(y: np.ndarray) -> np.ndarray:
    """Per column of ``y``: True when the spread is round-off of the column's magnitude (see module docstring)."""
    spread = np.ptp(y, axis=0)
    return spread <= _CONSTANT_RTOL * np.max(np.abs(y), axis=0)
