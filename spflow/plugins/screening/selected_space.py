"""The ``selected_space`` stage: the reduced parameter space a screening kept (Algorithm 1, step 10: "combine all
xi_Mi"), as a SPACE Dataset that ``lhs_design`` and the surrogate stages consume, with the screened space's parameter
map (which UTCHEM names each column sets) and its marginals (``distribution`` / ``distribution_parameters``) when it
recorded any."""

from __future__ import annotations

import xarray as xr

from spflow.core.errors import ParameterError
from spflow.core.stage import Stage, StageContext
from spflow.plugins.design.schemas import MAP_VARIABLES, SPACE

from .schemas import SCREENING


class SelectedSpace(Stage):
    name = "selected_space"
    version = "3"  # 3: keeps the screened space's marginals (issue #24)
    description = "the parameters a screening selected, as a parameter space"
    inputs = {"screening": SCREENING}
    output = SPACE

    def run(self, ctx: StageContext, screening: xr.Dataset) -> xr.Dataset:
        keep = screening["selected"].values.astype(bool)
        if not keep.any():
            raise ParameterError(f"stage 'selected_space': the screening selected no parameter "
                                 f"(rule: {screening.attrs.get('selection_rule', '?')}); lower its threshold or "
                                 "set top_k")
        laws = [k for k in ("distribution", "distribution_parameters") if k in screening]
        kept = ["lower", "upper", "default", "unit"] + [k for k in MAP_VARIABLES if k in screening] + laws
        out = screening[kept].isel(param=keep)
        out = out.drop_vars([c for c in out.coords if "qoi" in out[c].dims])
        out.attrs = {"distribution": "independent, per parameter in the variable 'distribution'" if laws else
                     "independent uniform",
                     "screening": f"{screening.attrs['method']} ({screening.attrs.get('selection_rule', '')})"}
        return out
