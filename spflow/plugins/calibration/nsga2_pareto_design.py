"""The ``pareto_design`` stage: the Pareto sets of an NSGA-II history match at stored generations, as one design.

Figs. 3.11-3.13 run the simulator at every point of the Pareto front after the first and the last generation and
draw the responses over the data. This stage turns fronts stored by ``nsga2_calibration`` (its ``snapshot``
generations, which always include the last one) into a ``design`` Dataset (dims sample, param) with a
``generation`` coordinate on ``sample`` telling which front each point belongs to, so one ordinary ``forward`` node
simulates them all — cached, and parallel over every point at once. The design carries the calibration's parameter
map (which UTCHEM names each column sets).
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from spflow.core.errors import ParameterError
from spflow.core.params import Param
from spflow.core.stage import Stage, StageContext
from spflow.plugins.calibration.nsga2_stage import NSGA2_CALIBRATION
from spflow.plugins.design.parameter_map import ParameterMap
from spflow.plugins.design.schemas import DESIGN

__all__ = ["ParetoDesign"]


class ParetoDesign(Stage):
    name = "pareto_design"
    version = "3"
    description = "the Pareto sets of an nsga2_calibration at stored generations, as one design"
    inputs = {"calibration": NSGA2_CALIBRATION}
    output = DESIGN
    params = {
        "generations": Param(list, [0], bounds=(0, None),
                             doc="stored snapshot generations (see the calibration's 'snapshot'); 0 = the last one"),
    }

    def run(self, ctx: StageContext, calibration: xr.Dataset) -> xr.Dataset:
        stored = [int(g) for g in calibration["snapshot"].values]
        wanted = list(dict.fromkeys(int(g) or max(stored) for g in self.params["generations"]))  # 0 -> last, once
        missing = [g for g in wanted if g not in stored]
        if missing or not wanted:
            raise ParameterError(f"stage 'pareto_design' parameter 'generations' = {self.params['generations']}: "
                                 f"{missing or 'none'} not stored; stored generations: {stored} (0 = the last)")
        fronts = []
        for g in wanted:
            snap = calibration.sel(snapshot=g)
            fronts.append(snap["front_designs"].values[: int(snap["front_size"])])
        values = np.concatenate(fronts)
        return ParameterMap.of(calibration).design(
            values, attrs={"design": f"Pareto sets of generations {wanted}"},
            units=calibration["param_unit"].values.astype(str).tolist(),
            generation=("sample", np.repeat(wanted, [len(f) for f in fronts])))
