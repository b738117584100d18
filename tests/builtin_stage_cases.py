"""Small inputs for every built-in stage (a two-parameter space, six design points, 10-cell forward runs, small
budgets): ``CASES`` maps each built-in stage to its parameters, inputs and NaN-as-missing ports. Shared by the
conformance kit's test over the built-ins and the units check of what every built-in stage writes."""

from __future__ import annotations

import tempfile
from functools import cached_property
from pathlib import Path

from spflow.core.plugins import get_registry
from spflow.core.stage import StageContext
from spflow.testing.small_inputs import small_design, small_observations, small_responses, small_space


class Small:
    """Small inputs for every built-in port, built once per module."""

    ctx = StageContext("conformance-inputs", verbose=False)

    def run(self, stage: str, inputs: dict | None = None, **params):
        return get_registry().stage(stage)(**params).run(self.ctx, **(inputs or {}))

    @cached_property
    def space(self):
        return small_space()

    @cached_property
    def design(self):
        return small_design(self.space)

    @cached_property
    def responses(self):
        return small_responses(self.design)

    @cached_property
    def observations(self):
        return small_observations(("BCF1", "BCF2"))

    @cached_property
    def surrogate(self):
        return self.run("pce", self.training, degree_max=2)

    @property
    def training(self):
        return {"space": self.space, "design": self.design, "responses": self.responses}

    @property
    def calibration_inputs(self):
        return {"surrogate": self.surrogate, "observations": self.observations, "space": self.space}

    @cached_property
    def screening(self):
        return self.run("morris_screening", {"space": self.space}, **MORRIS)

    @cached_property
    def calibration(self):
        return self.run("nsga2_calibration", self.calibration_inputs, **NSGA2)

    @cached_property
    def posterior(self):
        return self.run("mh_sampler", self.calibration_inputs, **MH)

    @cached_property
    def netcdf(self):
        path = Path(tempfile.mkdtemp(prefix="spflow-conformance-")) / "space.nc"
        self.space.to_netcdf(path)
        return str(path)


MORRIS = {"cells": 10, "trajectories": 2, "resamples": 10}
NSGA2 = {"population": 8, "generations": 2, "snapshots": [1, 2], "n_cross": 2, "held_out": ["BCF2"], "cells": 10}
MCMC = {"samples": 400, "burn": 100, "chains": 2, "variables": ["dp", "recovery"]}
MH = {**MCMC, "tune_interval": 50}
#: The diagnosis's default base model on 10 cells.
DIAGNOSE_BASE = {**get_registry().stage("diagnose").params["base"].default, "cells": 10}
LAB_FITS = ("fit_adsorption", "fit_desaturation", "fit_ift", "fit_me_viscosity", "fit_phase_behaviour",
            "fit_polymer_coreflood", "fit_polymer_rheology", "fit_tracer")

#: stage -> (small) -> (params, inputs, nan_as_missing). Observations hold NaN where nothing was measured (the
#: observations stage's documented padding), so stages reading them declare that port.
CASES = {
    "parameter_space": lambda s: ({"names": ["AD41", "CRK"], "relative": 0.3}, {}, ()),
    "lhs_design": lambda s: ({"samples": 5, "seed": 1}, {"space": s.space}, ()),
    "forward": lambda s: ({"experiments": ["BCF1"], "cells": 10}, {"design": s.design}, ()),
    "quantiles": lambda s: ({}, {"ensemble": s.responses}, ()),
    "observations": lambda s: ({"experiments": ["BCF1"]}, {}, ()),
    "load_netcdf": lambda s: ({"path": s.netcdf}, {}, ()),
    "pce": lambda s: ({"degree_max": 2}, s.training, ()),
    "gp": lambda s: ({"restarts": 1}, s.training, ()),
    "pck": lambda s: ({"restarts": 1, "degree_max": 2}, s.training, ()),
    "adaptive_pce": lambda s: ({"cells": 10, "n_initial": 5, "n_increment": 3, "n_max": 8, "degree_max": 2},
                               {"space": s.space}, ()),
    "surrogate_validation": lambda s: ({}, {"surrogate": s.surrogate, "design": small_design(s.space, 4, seed=2),
                                            "responses": small_responses(small_design(s.space, 4, seed=2))}, ()),
    "morris_screening": lambda s: (MORRIS, {"space": s.space}, ()),
    "sobol_screening": lambda s: ({"cells": 10, "samples": 4, "resamples": 10}, {"space": s.space}, ()),
    "selected_space": lambda s: ({}, {"screening": s.screening}, ()),
    "nsga2_calibration": lambda s: (NSGA2, s.calibration_inputs, ("observations",)),
    "pareto_design": lambda s: ({"generations": [2]}, {"calibration": s.calibration}, ()),
    "emcee_sampler": lambda s: (MCMC, s.calibration_inputs, ("observations",)),
    "mh_sampler": lambda s: (MH, s.calibration_inputs, ("observations",)),
    "posterior_predictive": lambda s: ({"experiments": ["BCF1"], "draws": 3, "cells": 10},
                                       {"posterior": s.posterior, "space": s.space, "observations": s.observations},
                                       ("observations",)),
    "slug_design": lambda s: ({"n_init": 3, "max_iter": 1, "min_iter": 0, "n_fronts": 2, "knee_draws": 1, "cells": 10,
                               "pv_step": 0.1, "snapshots": [1]}, {"posterior": s.posterior}, ()),
    "priors": lambda s: ({"names": ["AP1", "ALPHAL1"]}, {"fit_polymer_rheology": s.run("fit_polymer_rheology"),
                                                        "fit_tracer": s.run("fit_tracer")}, ()),
    "diagnose": lambda s: ({"base": DIAGNOSE_BASE, "max_nfev": 2, "replicates": 10, "numerical_error": False,
                            "shortlist": 1, "first_step_refits": "shortlist", "max_effects": 1,
                            "subset_pool": 1}, {}, ()),
    **{name: (lambda s: ({}, {}, ())) for name in LAB_FITS},
}
