"""The calibration problem of §3.6 as a pymoo ``Problem``: minimise Q = [q_1, q_2] (Eq. 3.17) over the prior box.

Each objective is the half squared misfit of Eq. 3.16 between the surrogate's prediction P(ξ) of one training
variable (thesis: s = 1 cumulative recovery, s = 2 pressure drop of BCF1) and its observation, summed over the
training corefloods when there are several (e.g. BCF1 + BCF2: one objective per variable, as in Eq. 3.17). The problem
is vectorised: pymoo hands a whole generation's offspring (n, n_param) to ``_evaluate`` and the surrogate is called
once for all of them.

The decision variables are ordered like the ``space`` (the prior box, Table 3.2); the surrogate may store its
parameters in another order, so columns are permuted before each prediction.
"""

from __future__ import annotations

import numpy as np
from pymoo.core.problem import Problem

from spflow.core.errors import ParameterError
from spflow.plugins.calibration.aligned_data import align
from spflow.plugins.calibration.nsga2_misfits import half_squared_misfit
from spflow.plugins.surrogates.contract import Surrogate

__all__ = ["SurrogateMisfitProblem"]


class SurrogateMisfitProblem(Problem):
    """Objectives Σ_e ½‖P_e(ξ) − y_e‖² per variable over the training experiments on a surrogate, over
    ``lower <= ξ <= upper``. ``pairs`` lists the (variable, experiment) blocks, variable-major."""

    def __init__(self, surrogate: Surrogate, observations, names: list[str], lower: np.ndarray, upper: np.ndarray,
                 variables: list[str], experiments: list[str]):
        names = [str(n) for n in names]
        if sorted(names) != sorted(surrogate.names):
            raise ParameterError(f"calibration space parameters {names} differ from the surrogate's {surrogate.names}")
        lower, upper = np.asarray(lower, dtype=float), np.asarray(upper, dtype=float)
        self.order = np.array([names.index(n) for n in surrogate.names])
        tol = 1e-9 * (surrogate.upper - surrogate.lower)
        beyond = (lower[self.order] < surrogate.lower - tol) | (upper[self.order] > surrogate.upper + tol)
        outside = [n for n, out in zip(surrogate.names, beyond) if out]
        if outside:
            raise ParameterError(f"calibration space leaves the surrogate's training box for {outside}: a surrogate "
                                 "must not be extrapolated")
        self.surrogate = surrogate
        self.n_experiments = len(experiments)
        self.pairs = [(str(v), str(e)) for v in variables for e in experiments]
        self.aligned = align(surrogate.outputs, observations, self.pairs)
        super().__init__(n_var=len(names), n_obj=len(variables), xl=lower, xu=upper, vtype=float)

    def mean(self, x: np.ndarray) -> np.ndarray:
        """The surrogate's mean prediction P(ξ) at points ``x`` (n, n_param) in space order: (n, n_output)."""
        mean, _ = self.surrogate.predict(np.atleast_2d(x)[:, self.order])
        return mean

    def objectives(self, x: np.ndarray) -> np.ndarray:
        """Q(ξ) for points ``x`` (n, n_param) in space order: (n, n_objective)."""
        per_pair = half_squared_misfit(self.mean(x), self.aligned, self.pairs)
        return per_pair.reshape(len(per_pair), -1, self.n_experiments).sum(axis=-1)

    def _evaluate(self, x, out, *args, **kwargs):
        out["F"] = self.objectives(x)
