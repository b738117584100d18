"""The ``adaptive_pce`` stage: grow the training design until the PCE's LOO error settles (thesis Algorithm 2).

Starting from ``n_initial`` Latin-hypercube points of the parameter space, the stage runs the simulator (through the
``forward`` stage class, so the runs are exactly those a ``forward`` node would make), fits the degree-adaptive PCE
(:mod:`.degree_adaptive`) and adds ``n_increment`` new points per iteration until the change of ε_LOO^mean (Eq. 3.9)
between two iterations is below ``tolerance`` (thesis: Δε_LOO^mean < 5e-4, Algorithm 2 line 2) or ``n_max`` runs
are spent. Each increment is a fresh Latin hypercube (seeded ``seed + iteration``) appended to the earlier points, so
no simulation is thrown away; the union is no longer a Latin hypercube, only close to one. When the space records
marginals (:mod:`.training_data`), each column of the hypercube goes through its marginal's quantile function, so the
design is drawn from them (the ``lhs_design`` stage's :func:`~spflow.plugins.design.latin_hypercube.latin_hypercube`),
and the PCE is fitted under them.

The output is the final surrogate (kind ``pce``) plus the history over the design sizes (dim ``n_s``):
ε_LOO^mean, the mean modified LOO, ε_emp^mean (Eq. 3.10) and the selected degree.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import xarray as xr

from spflow.core.errors import ParameterError
from spflow.core.params import Param
from spflow.core.stage import Stage, StageContext
from spflow.plugins.design.latin_hypercube import latin_hypercube
from spflow.plugins.design.parameter_map import ParameterMap
from spflow.plugins.design.schemas import SPACE
from spflow.plugins.forward.experiments import forward_experiments
from spflow.plugins.forward.stage import Forward

from .contract import STORED_SURROGATE, with_parameter_units
from .pce_model import PCE
from .pce_stage import PCE_PARAMS, check_cv_folds, check_lists, fit_options
from .training_data import training_set

__all__ = ["AdaptivePCE"]

_FORWARD_PARAMS = ("experiments", "fixed", "effects", "cells", "pv_step", "scheme")


class AdaptivePCE(Stage):
    name = "adaptive_pce"
    # 2: the pce fit's degree cap 15, basis-size limit and corrected-LOO error variance; 3: + UDUNITS units per
    # element; 4: the space's marginals honoured and recorded (issue #24); 5: default degree_max 20 (was 15); 6: the
    # pce stage's cv_folds (attrs cv_folds, error_estimate) and LARS path scaled to the output (lars.PATH_SCALE); 7:
    # the LARS solver keeps the one-SE model of its path (lars.PREFIX_RULES)
    version = "7"
    description = "PCE proxy on a growing LHS design until the mean LOO error settles (Algorithm 2)"
    inputs = {"space": SPACE}
    output = STORED_SURROGATE
    params = {
        **PCE_PARAMS,
        **{k: v for k, v in Forward.params.items() if k in _FORWARD_PARAMS and k != "experiments"},
        "experiments": replace(PCE_PARAMS["experiments"],
                               doc="experiments simulated and approximated: bundled names or {name, schedule, params} "
                                   "mappings (as the forward stage's)"),
        "n_initial": Param(int, 50, bounds=(3, 100_000), doc="first design size (thesis: 50)"),
        "n_increment": Param(int, 50, bounds=(1, 100_000), doc="points added per iteration"),
        "n_max": Param(int, 500, bounds=(3, 1_000_000), doc="simulation budget (largest design size)"),
        "tolerance": Param(float, 5e-4, bounds=(0.0, 1.0), doc="stop when |Δ ε_LOO^mean| < this (thesis: 5e-4)"),
        "seed": Param(int, 0, bounds=(0, 2**32 - 1), doc="seed of the first LHS batch (batch k uses seed + k)"),
    }

    def __init__(self, **params):
        super().__init__(**params)
        self._names = [e.name for e in forward_experiments(self.params["experiments"], self.params["fixed"])]
        check_lists(self.name, self.params | {"experiments": self._names})
        check_cv_folds(self.name, self.params)
        if self.params["n_initial"] > self.params["n_max"]:
            raise ParameterError(f"stage 'adaptive_pce': n_initial = {self.params['n_initial']} exceeds n_max = "
                                 f"{self.params['n_max']}")
        self._forward = Forward(**{k: self.params[k] for k in _FORWARD_PARAMS})

    @classmethod
    def code_fingerprint(cls) -> str:
        """The stage's source plus the ``forward`` stage's (which covers every simulator source file)."""
        return f"{super().code_fingerprint()}-{Forward.code_fingerprint()}"

    def _batch(self, space: xr.Dataset, size: int, iteration: int) -> xr.Dataset:
        values, _ = latin_hypercube(space, size, self.params["seed"] + iteration, where=f"stage {self.name!r}")
        return ParameterMap.of(space).design(values)

    def run(self, ctx: StageContext, space: xr.Dataset) -> xr.Dataset:
        p = self.params
        designs, responses, rows = [], [], []
        model, size, iteration = None, p["n_initial"], 0
        while True:
            batch = self._batch(space, size, iteration)
            designs.append(batch)
            responses.append(self._forward.run(ctx, design=batch))
            size_so_far = sum(d.sizes["sample"] for d in designs)
            design = xr.concat(designs, dim="sample", data_vars="minimal").assign_coords(
                sample=np.arange(size_so_far))
            response = xr.concat(responses, dim="sample", data_vars="minimal", coords="minimal",
                                 compat="override").assign_coords(sample=design["sample"].values)
            data = training_set(space, design, response, list(p["variables"]), self._names)
            model = PCE.fit(data.names, data.lower, data.upper, data.outputs, data.x, data.y, inputs=data.inputs,
                            **fit_options(p, ctx))
            rows.append((data.x.shape[0], np.mean(model.loo), np.mean(model.modified_loo), np.mean(model.empirical),
                         model.info["degree"]))
            n = data.x.shape[0]
            settled = len(rows) > 1 and abs(rows[-1][1] - rows[-2][1]) < p["tolerance"]
            if settled or n >= p["n_max"]:
                break
            size, iteration = min(p["n_increment"], p["n_max"] - n), iteration + 1
        n_s, loo, modified, emp, degree = (np.array(c) for c in zip(*rows))
        ds = with_parameter_units(model.to_dataset(), space)
        ds = ds.assign_coords(n_s=("n_s", n_s, {"units": "1", "long_name": "training design size"}))
        ds["loo_history"] = ("n_s", loo, {"units": "1", "long_name": "mean LOO error over outputs (Eq. 3.9)"})
        ds["modified_loo_history"] = ("n_s", modified, {"units": "1", "long_name": "mean modified LOO error"})
        ds["empirical_history"] = ("n_s", emp, {"units": "1", "long_name": "mean empirical error (Eq. 3.10)"})
        ds["degree_history"] = ("n_s", degree.astype(np.int64), {"units": "1", "long_name": "selected degree"})
        ds.attrs["converged"] = int(settled)
        ds.attrs["tolerance"] = p["tolerance"]
        return ds
