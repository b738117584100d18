"""The ``lhs_design`` stage: a Latin hypercube design (scipy.stats.qmc) scaled to a parameter space's bounds; the
design carries the space's parameter map (:mod:`.parameter_map`: which UTCHEM names each column sets, its scale)."""

from __future__ import annotations

import xarray as xr

from spflow.core.params import Param
from spflow.core.stage import Stage, StageContext
from spflow.plugins.design.parameter_map import ParameterMap
from spflow.plugins.design.schemas import DESIGN_WITH_UNITS, SPACE


class LatinHypercubeDesign(Stage):
    name = "lhs_design"
    version = "3"
    description = "Latin hypercube sample of a parameter space"
    inputs = {"space": SPACE}
    output = DESIGN_WITH_UNITS
    params = {
        "samples": Param(int, 100, bounds=(1, 10_000_000), doc="number of design points"),
        "seed": Param(int, 0, bounds=(0, 2**32 - 1), doc="random seed"),
        "optimization": Param(str, "none", choices=["none", "random-cd", "lloyd"], doc="scipy LHS optimisation"),
    }

    def run(self, ctx: StageContext, space: xr.Dataset) -> xr.Dataset:
        opt = None if self.params["optimization"] == "none" else self.params["optimization"]
        from scipy.stats import qmc  # SciPy's statistics load when a design is drawn

        sampler = qmc.LatinHypercube(d=space.sizes["param"], rng=self.params["seed"], optimization=opt)
        unit = sampler.random(self.params["samples"])
        values = qmc.scale(unit, space["lower"].values, space["upper"].values)
        return ParameterMap.of(space).design(values, attrs={"design": "latin hypercube", "seed": self.params["seed"]},
                                             units=space["unit"].values.tolist())
