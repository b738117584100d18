"""The ``lhs_design`` stage: a Latin hypercube design (scipy.stats.qmc) of a parameter space, drawn from the space's
marginals; the design carries the space's parameter map (:mod:`.parameter_map`: which UTCHEM names each column sets,
its scale).

The hypercube is drawn on [0, 1]^d: each column has exactly one point in each of the n strata [k/n, (k+1)/n). A
space that records no marginals has each column scaled to its range, lower + (upper − lower) u, as the thesis's
uniform designs. A space that records them (``distribution`` / ``distribution_parameters``, e.g. the ``priors``
stage's truncated normals; each law's support is the column's range) has each column mapped through its marginal's
quantile function (:func:`~spflow.plugins.surrogates.input_marginals.from_unit_hypercube`, the isoprobabilistic
transform), so each column then has exactly one point in each stratum of its marginal's cdf and the design is a
stratified sample of the marginals (McKay, Beckman & Conover 1979). A uniform marginal's quantile function is the
same scaling, so a space of uniform marginals gives the box's design to the last bit. The laws are printed
(``verbose``) and recorded in the design, as the screening stages record them: attr ``marginals`` and, when the space
records them, the variables ``distribution`` / ``distribution_parameters``.
"""

from __future__ import annotations

import sys

import numpy as np
import xarray as xr

from spflow.core.params import Param
from spflow.core.stage import Stage, StageContext
from spflow.plugins.design.parameter_map import ParameterMap
from spflow.plugins.design.schemas import DESIGN_WITH_UNITS, SPACE
from spflow.plugins.surrogates.input_marginals import Marginal, from_unit_hypercube, marginal_variables
from spflow.plugins.surrogates.training_data import describe_marginals, space_marginals

__all__ = ["LatinHypercubeDesign", "latin_hypercube"]


def latin_hypercube(space: xr.Dataset, samples: int, seed: int, optimization: str | None = None,
                    where: str = "stage 'lhs_design'") -> tuple[np.ndarray, list[Marginal] | None]:
    """(points (``samples``, d) of a Latin hypercube of ``space`` drawn from its marginals (module docstring), the
    marginals the space records or None); ``optimization``: scipy's LHS optimisation (None, "random-cd", "lloyd");
    ``where`` starts the error messages."""
    from scipy.stats import qmc  # SciPy's statistics load when a design is drawn

    names = [str(n) for n in space["param"].values]
    lower, upper = space["lower"].values.astype(float), space["upper"].values.astype(float)
    recorded = space_marginals(space, names, lower, upper, where)
    unit = qmc.LatinHypercube(d=len(names), rng=seed, optimization=optimization).random(samples)
    if recorded is None:
        return qmc.scale(unit, lower, upper), None
    # a quantile function's round-off may step past its support's end by an ulp: kept on the range
    return np.clip(from_unit_hypercube(recorded, unit), lower, upper), recorded


class LatinHypercubeDesign(Stage):
    name = "lhs_design"
    version = "4"  # 4: drawn from the space's marginals, recorded (uniform or none: the same design; issue #24)
    description = "Latin hypercube sample of a parameter space, under its marginals"
    inputs = {"space": SPACE}
    output = DESIGN_WITH_UNITS
    params = {
        "samples": Param(int, 100, bounds=(1, 10_000_000), doc="number of design points"),
        "seed": Param(int, 0, bounds=(0, 2**32 - 1), doc="random seed"),
        "optimization": Param(str, "none", choices=["none", "random-cd", "lloyd"], doc="scipy LHS optimisation"),
    }

    def run(self, ctx: StageContext, space: xr.Dataset) -> xr.Dataset:
        opt = None if self.params["optimization"] == "none" else self.params["optimization"]
        values, recorded = latin_hypercube(space, self.params["samples"], self.params["seed"], opt,
                                           f"stage {self.name!r}")
        names = [str(n) for n in space["param"].values]
        printed, marginals = describe_marginals(names, space["lower"].values, space["upper"].values, recorded)
        if ctx.verbose:
            print(f"[{ctx.node}] Latin hypercube under{printed}", file=sys.stderr, flush=True)
        design = ParameterMap.of(space).design(values, attrs={"design": "latin hypercube", "seed": self.params["seed"],
                                                              "marginals": marginals},
                                               units=space["unit"].values.tolist())
        return design if recorded is None else design.assign(marginal_variables(recorded))
