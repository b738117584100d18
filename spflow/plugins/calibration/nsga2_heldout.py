"""Cross-validation of a Pareto set on held-out corefloods with the simulator (Algorithm 3, lines 14-15).

The surrogate is built for the training coreflood only, so the Pareto-optimal parameter vectors are run through the
forward model (the ``forward`` stage, which parallelises over points with the node's joblib budget) on the held-out
injection schedules (thesis: BCF2, BCF3), and each simulated series is compared with its measurement by the relative
L2 misfit of :func:`~spflow.plugins.calibration.nsga2_misfits.relative_l2_misfit`. σ_loss, the stopping quantity of
Algorithm 3, is the mean of these misfits over the Pareto set, the held-out corefloods and the variables (§3.7).
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from spflow.core.stage import StageContext
from spflow.plugins.calibration.aligned_data import align
from spflow.plugins.calibration.nsga2_misfits import relative_l2_misfit
from spflow.plugins.design.parameter_map import ParameterMap
from spflow.plugins.forward.experiments import forward_experiments
from spflow.plugins.forward.stage import Forward
from spflow.plugins.surrogates.outputs import stack_outputs

__all__ = ["HeldOutCheck"]


class HeldOutCheck:
    """Simulate parameter vectors on held-out corefloods and return their relative L2 misfits to the observations.

    ``forward`` is a configured :class:`Forward` stage (its ``experiments`` are the held-out corefloods, its
    ``fixed``/``effects``/``cells``/``pv_step`` the model the surrogate was trained on); ``observations`` has dims
    (experiment, pv) on the same PV grid spacing. Construction checks that every (variable, experiment) pair has
    observations, so a misnamed experiment fails before the optimisation starts. ``columns``: the parameter map of
    the points' columns (a list of UTCHEM names: each column sets its own parameter).
    """

    def __init__(self, forward: Forward, observations: xr.Dataset, variables: list[str],
                 columns: ParameterMap | list[str]):
        self.forward = forward
        self.observations = observations
        self.variables = [str(v) for v in variables]
        self.experiments = [e.name for e in forward_experiments(forward.params["experiments"], forward.params["fixed"])]
        self.columns = columns if isinstance(columns, ParameterMap) else ParameterMap.identity(columns)
        self.pairs = [(v, e) for e in self.experiments for v in self.variables]
        # the observations themselves as a one-sample "prediction": align() then validates every pair up front
        _, index = stack_outputs(observations.expand_dims(sample=1), self.variables, self.experiments)
        align(index, observations, self.pairs)

    def misfits(self, ctx: StageContext, points: np.ndarray) -> np.ndarray:
        """Relative L2 misfits of ``points`` (n, n_param), shape (n, n_experiment, n_variable)."""
        design = self.columns.design(points)
        responses = self.forward.run(ctx, design=design)
        prediction, index = stack_outputs(responses, self.variables, self.experiments)
        aligned = align(index, self.observations, self.pairs)
        rel = relative_l2_misfit(prediction, aligned, self.pairs)
        return rel.reshape(len(points), len(self.experiments), len(self.variables))
