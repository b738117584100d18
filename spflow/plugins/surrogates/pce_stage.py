"""The ``pce`` stage: a degree-adaptive PCE proxy of simulator responses (thesis §3.5, Algorithm 2 lines 5-10).

Inputs: the parameter ``space`` (a uniform box, or the marginals it records: :mod:`.training_data`), the training
``design`` on it and the forward stage's ``responses`` at the design points. Output: the fitted surrogate Dataset
(:data:`~.contract.STORED_SURROGATE`, kind ``pce``) with per-output ``loo``, ``modified_loo`` and ``empirical`` errors
(and ``cv_error`` with ``cv_folds`` >= 2; ``attrs["error_estimate"]`` names the one the proxy reports) and their means
over outputs (ε^mean, Eqs. 3.9-3.10) in attrs, with ``degree_cap`` (the largest degree the search could try) and
``degree_cap_warning`` ("" unless the selected degree is that cap, :class:`~spflow.core.errors.DegreeCapWarning`).
"""

from __future__ import annotations

import xarray as xr

from spflow.core.errors import ParameterError
from spflow.core.params import Param
from spflow.core.stage import Stage, StageContext
from spflow.plugins.design.schemas import DESIGN, SPACE
from spflow.plugins.forward.stage import RESPONSE_UNITS, RESPONSES

from .contract import STORED_SURROGATE, with_parameter_units
from .degree_adaptive import DEGREE_MAX, MAX_TERMS_RATIO, SOLVERS
from .pce_model import PCE
from .training_data import training_set

__all__ = ["PCEStage", "PCE_PARAMS", "fit_options", "check_lists", "check_cv_folds"]

#: Parameters of the PCE fit, shared with ``adaptive_pce``.
PCE_PARAMS = {
    "variables": Param(list, ["dp", "recovery"], choices=sorted(RESPONSE_UNITS),
                       doc="response variables to approximate (each a time series on the PV grid)"),
    "experiments": Param(list, ["BCF1"], doc="experiments whose responses are approximated"),
    "degree_max": Param(int, DEGREE_MAX, bounds=(1, 20),
                        doc="largest total degree p tried (the thesis used 5; the search stops earlier by itself once "
                            "two degrees in a row do not improve the corrected LOO)"),
    "max_terms_ratio": Param(float, MAX_TERMS_RATIO, bounds=(1.0, 1000.0),
                             doc="largest candidate basis tried, in terms per training run (never below 1000 terms)"),
    "q": Param(float, 0.9, bounds=(0.05, 1.0), doc="q-norm of the hyperbolic truncation (thesis: 0.9)"),
    "solver": Param(str, "ols", choices=list(SOLVERS), doc="OLS or hybrid LARS (sparse)"),
    "target_loo": Param(float, 0.0, bounds=(0.0, 1.0),
                        doc="stop raising the degree once the mean modified LOO error is <= this"),
    "cv_folds": Param(int, 0, bounds=(0, 100_000),
                      doc="0: the proxy reports its corrected LOO error; K >= 2: the K-fold cross-validation error of "
                          "the whole adaptive fit (about K times the fit's cost; docs/surrogates.md, The reported "
                          "error)"),
}


def fit_options(params, ctx: StageContext) -> dict:
    """Keyword arguments of :meth:`.pce_model.PCE.fit` (those of :func:`.degree_adaptive.fit_pce` and ``cv_folds``)
    from a stage's parameters (progress: degrees tried)."""
    return {"degree_max": params["degree_max"], "q": params["q"], "solver": params["solver"],
            "target_loo": params["target_loo"], "max_terms_ratio": params["max_terms_ratio"],
            "cv_folds": params["cv_folds"],
            "parallel": ctx.parallel() if ctx.n_jobs > 1 else None,
            "progress": lambda degree, degree_max: ctx.report_progress(degree, degree_max, "degrees")}


def check_lists(stage: str, params) -> None:
    """``variables`` and ``experiments`` must be non-empty lists without repeats (checked before any work)."""
    for name in ("variables", "experiments"):
        values = params[name]
        if not values or len(set(values)) != len(values):
            raise ParameterError(f"stage {stage!r} parameter {name!r} must be a non-empty list without repeats, "
                                 f"got {values!r}")


def check_cv_folds(stage: str, params) -> None:
    """``cv_folds`` is 0 or >= 2 (checked before any work; the fold sizes are checked against the design when the fit
    starts, :func:`.pce_cross_validation.check_folds`)."""
    if params["cv_folds"] == 1:
        raise ParameterError(f"stage {stage!r} parameter 'cv_folds' must be 0 (report the corrected LOO) or >= 2 "
                             f"(K-fold cross-validation of the whole fit), got 1")


class PCEStage(Stage):
    name = "pce"
    # 2: degree cap 15 + basis-size limit, corrected LOO as the error variance, degree_cap attrs; 3: + UDUNITS units
    # per element; 4: the space's marginals honoured and recorded (distribution, distribution_parameters; issue #24);
    # 5: default degree_max 20 (was 15); 6: cv_folds, attrs cv_folds and error_estimate (+ cv_error when K >= 2), the
    # LARS path scaled to the output (lars.PATH_SCALE: small-valued outputs were cut short); 7: the LARS solver keeps
    # the one-SE model of its path (lars.PREFIX_RULES)
    version = "7"
    description = "degree-adaptive polynomial chaos proxy (OLS or hybrid LARS, chosen by corrected LOO) of responses"
    inputs = {"space": SPACE, "design": DESIGN, "responses": RESPONSES}
    output = STORED_SURROGATE
    params = PCE_PARAMS

    def __init__(self, **params):
        super().__init__(**params)
        check_lists(self.name, self.params)
        check_cv_folds(self.name, self.params)

    def run(self, ctx: StageContext, space: xr.Dataset, design: xr.Dataset, responses: xr.Dataset) -> xr.Dataset:
        data = training_set(space, design, responses, list(self.params["variables"]), list(self.params["experiments"]))
        model = PCE.fit(data.names, data.lower, data.upper, data.outputs, data.x, data.y, inputs=data.inputs,
                        **fit_options(self.params, ctx))
        return with_parameter_units(model.to_dataset(), space)
