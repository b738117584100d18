"""The ``morris_screening`` stage: elementary-effects screening (Morris 1991, mu* of Campolongo et al. 2007) with
SALib (:mod:`.morris`), a cheaper alternative to ``sobol_screening`` with the same inputs, selection rule and layout.

Per design of d parameters it runs r (d + 1) simulations for r ``trajectories``. mu* has the QoI's unit, so the
selection score of a parameter is mu* divided by the largest mu* among the parameters screened in the same design
(its group in ``per_group`` mode), maximised over the ``select_on`` QoIs: 1 for the most influential parameter of
each design, near 0 for inert ones.
"""

from __future__ import annotations

import xarray as xr

from spflow.core.params import Param

from .morris import check_morris_design, morris_indices, morris_sample
from .schemas import MORRIS_SCREENING
from .screening_stage import SCREENING_PARAMS, ScreeningStage


class MorrisScreening(ScreeningStage):
    name = "morris_screening"
    # 5: the space's marginals (uniform: the box, unchanged design; issue #24); every unit in UDUNITS form (issue 23)
    version = "5"
    description = "Morris elementary-effects screening (SALib) of a parameter space on the forward model"
    output = MORRIS_SCREENING
    method = "morris"
    params = {
        **SCREENING_PARAMS,
        "trajectories": Param(int, 20, bounds=(2, 100_000), doc="number of one-at-a-time trajectories r"),
        "levels": Param(int, 4, bounds=(2, 100), doc="grid levels p of the Morris design (even)"),
    }

    def __init__(self, **params):
        super().__init__(**params)
        check_morris_design(self.params["trajectories"], self.params["levels"], f"stage {self.name!r} parameter")

    def _runs(self, d):
        return self.params["trajectories"] * (d + 1)

    def _sample(self, names, lower, upper, rng, inputs):
        return morris_sample(names, lower, upper, self.params["trajectories"], levels=self.params["levels"], seed=rng,
                             inputs=inputs)

    def _analyse(self, names, x, y, lower, upper, rng) -> xr.Dataset:
        return morris_indices(x, y, names, lower, upper, levels=self.params["levels"],
                              conf_level=self.params["conf_level"], resamples=self.params["resamples"], seed=rng)

    def _score(self, part, use):
        mu_star = part["mu_star"].isel(qoi=use)
        top = mu_star.max("param")
        return (mu_star / top.where(top > 0)).fillna(0.0).max("qoi")

    def _attrs(self):
        return {"trajectories": self.params["trajectories"], "levels": self.params["levels"]}
