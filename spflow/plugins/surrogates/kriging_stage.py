"""The ``pck`` and ``gp`` stages: PC-Kriging (thesis §3.8) and a plain GP proxy of simulator responses.

Same inputs and output as the ``pce`` stage -- the parameter ``space``, the training ``design`` and the forward
stage's ``responses`` in; a :data:`~.contract.STORED_SURROGATE` Dataset out -- so a pipeline swaps the proxy with
``Pipeline.set_stage``. The output stores each output's Kriging LOO error (``loo``) and their mean (ε_LOO^mean,
Eq. 3.9) in ``attrs["loo_mean"]``.
"""

from __future__ import annotations

import xarray as xr

from spflow.core.params import Param
from spflow.core.stage import Stage, StageContext
from spflow.plugins.design.schemas import DESIGN, SPACE
from spflow.plugins.forward.stage import RESPONSES

from .contract import STORED_SURROGATE, with_parameter_units
from .gp_model import GP
from .kriging import KERNELS
from .kriging_surrogate import NUGGET, RESTARTS, SHARING
from .pce_stage import PCE_PARAMS, check_lists
from .pck_model import PCK
from .pck_modes import MODES
from .training_data import training_set

__all__ = ["PCKStage", "GPStage", "KRIGING_PARAMS"]

#: Parameters common to both Kriging stages.
KRIGING_PARAMS = {
    "variables": PCE_PARAMS["variables"],
    "experiments": PCE_PARAMS["experiments"],
    "kernel": Param(str, "gaussian", choices=sorted(KERNELS),
                    doc="correlation: gaussian = squared exponential (thesis Eq. 3.20) or matern52"),
    "share": Param(str, "output", choices=list(SHARING),
                   doc="one set of length scales per output column, or per variable (~20x cheaper to evaluate)"),
    "restarts": Param(int, RESTARTS, bounds=(1, 100),
                      doc="L-BFGS-B starts of the likelihood maximisation (Eq. 3.21)"),
    "seed": Param(int, 0, bounds=(0, 2**32 - 1), doc="seed of the random restarts"),
    "nugget": Param(float, NUGGET, bounds=(0.0, 0.1), doc="added to the correlation matrix's diagonal"),
}


class _KrigingStage(Stage):
    """Common part: read the training data, fit with the subclass's ``_fit(data, options)``, store."""

    inputs = {"space": SPACE, "design": DESIGN, "responses": RESPONSES}
    output = STORED_SURROGATE

    def __init__(self, **params):
        super().__init__(**params)
        check_lists(self.name, self.params)

    def run(self, ctx: StageContext, space: xr.Dataset, design: xr.Dataset, responses: xr.Dataset) -> xr.Dataset:
        data = training_set(space, design, responses, list(self.params["variables"]), list(self.params["experiments"]))
        options = {k: self.params[k] for k in ("kernel", "share", "restarts", "seed", "nugget")}
        options["parallel"] = ctx.parallel() if ctx.n_jobs > 1 else None
        options["progress"] = lambda groups: ctx.progress(groups, what="length-scale fits")
        options["inputs"] = data.inputs  # the space's marginals (None: uniform on the box)
        return with_parameter_units(self._fit(data, options).to_dataset(), space)


class PCKStage(_KrigingStage):
    name = "pck"
    # 2: the trend's hybrid LARS ranks by the LASSO-modified path (issue #24); 3: + UDUNITS units per element; 4: the
    # space's marginals honoured and recorded (issue #24); 5: nugget 1e-8 -> 1e-12, length scales up to 10^4 (#24);
    # 6: the trend's LARS path scaled to the output (lars.PATH_SCALE: small-valued outputs were cut short)
    version = "6"
    description = "PC-Kriging proxy (universal Kriging on a hybrid-LARS polynomial-chaos trend, ML length scales)"
    params = {
        **KRIGING_PARAMS,
        "mode": Param(str, "sequential", choices=list(MODES),
                      doc="trend = all LARS-selected polynomials, or the LOO-best LARS-ranked prefix"),
        "degree_max": Param(int, 3, bounds=(1, 20), doc="largest total degree of the trend's sparse PCE"),
        "q": PCE_PARAMS["q"],
    }

    def _fit(self, data, options: dict) -> PCK:
        return PCK.fit(data.names, data.lower, data.upper, data.outputs, data.x, data.y, mode=self.params["mode"],
                       degree_max=self.params["degree_max"], q=self.params["q"], **options)


class GPStage(_KrigingStage):
    name = "gp"
    # 3: the space's marginals honoured (kernel in their reference variables) and recorded; 4: nugget 1e-8 -> 1e-12,
    # length scales up to 10^4 (issue #24)
    version = "4"
    description = "plain Gaussian-process proxy (ordinary Kriging, ML length scales)"
    params = KRIGING_PARAMS

    def _fit(self, data, options: dict) -> GP:
        return GP.fit(data.names, data.lower, data.upper, data.outputs, data.x, data.y, **options)
