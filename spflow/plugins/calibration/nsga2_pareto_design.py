"""The ``pareto_design`` stage: the Pareto sets of an NSGA-II history match at stored generations, as one design.

Figs. 3.11-3.13 run the simulator at every point of the Pareto front after the first and the last generation and
draw the responses over the data. This stage turns fronts stored by ``nsga2_calibration`` (its ``snapshot``
generations, which always include the last one) into a ``design`` Dataset (dims sample, param) with a
``generation`` coordinate on ``sample`` telling which front each point belongs to, so one ordinary ``forward`` node
simulates them all — cached, and parallel over every point at once. The design carries the calibration's parameter
map (which UTCHEM names each column sets).

``front_designs`` stores fronts of different sizes NaN-padded to a common ``member`` length: the members after a
snapshot's ``front_size`` are padding and are dropped; a NaN inside the first ``front_size`` members is a broken
calibration and is refused (:class:`~spflow.core.errors.ParameterError` naming the snapshot and the member) before it
can reach the design.
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from spflow.core.errors import ParameterError
from spflow.core.params import Param
from spflow.core.stage import Stage, StageContext
from spflow.plugins.calibration.nsga2_stage import NSGA2_CALIBRATION
from spflow.plugins.design.parameter_map import ParameterMap
from spflow.plugins.design.schemas import DESIGN_WITH_UNITS

__all__ = ["ParetoDesign"]


class ParetoDesign(Stage):
    name = "pareto_design"
    version = "4"  # 4: every unit in UDUNITS form (issue 23)
    description = "the Pareto sets of an nsga2_calibration at stored generations, as one design"
    inputs = {"calibration": NSGA2_CALIBRATION}
    output = DESIGN_WITH_UNITS
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
        fronts = [_front(calibration, g) for g in wanted]
        values = np.concatenate(fronts)
        return ParameterMap.of(calibration).design(
            values, attrs={"design": f"Pareto sets of generations {wanted}"},
            units=calibration["param_unit"].values.astype(str).tolist(),
            generation=("sample", np.repeat(wanted, [len(f) for f in fronts]),
                        {"units": "1", "long_name": "NSGA-II generation of the front"}))


def _front(calibration: xr.Dataset, generation: int) -> np.ndarray:
    """The Pareto set stored for snapshot ``generation``: its first ``front_size`` members (the rest is NaN padding),
    each of them finite."""
    snap = calibration.sel(snapshot=generation)
    size = int(snap["front_size"])
    front = np.asarray(snap["front_designs"].values[:size], dtype=float)
    bad = np.flatnonzero(~np.isfinite(front).all(axis=1))
    if bad.size:
        member = int(bad[0])
        params = [str(p) for p, ok in zip(calibration["param"].values, np.isfinite(front[member])) if not ok]
        raise ParameterError(f"stage 'pareto_design' input 'calibration': 'front_designs' at snapshot {generation}, "
                             f"member {member} is not finite in {params} ({bad.size} such member(s) of the "
                             f"{size} in that front); NaN is allowed only as the padding after 'front_size'")
    return front
