"""The ``parameter_space`` stage: uniform bounds on calibrated parameters, one design column each.

A column (``names`` entry) is a UTCHEM name or the label of a calibrated parameter that ``ranges`` defines
(:mod:`.calibrated_parameter`): ``label = [low, high]`` for the one UTCHEM name ``label``, or ``label = {names =
[...], range = [low, high], scale = "linear" | "log"}`` for one value setting several parameters (a study's
``[parameters.calibrated]``, :attr:`spflow.study.Study.parameter_space`). A UTCHEM name without a range gets
``relative`` ± fraction around its calibrated default (the thesis's ±20 % rule, Chapter 3.4), clipped to its physical
bounds. The output records which UTCHEM names each column sets and its scale (:mod:`.parameter_map`); a log-scale
column's bounds, default (clipped into the range) and unit are those of log10 of the value.
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from spflow.core.cf_metadata import UNITS_VARIABLE, udunits
from spflow.core.errors import ParameterError
from spflow.core.params import Param
from spflow.core.stage import Stage, StageContext
from spflow.plugins.design.calibrated_parameter import CalibratedParameter, calibrated_parameter
from spflow.plugins.design.parameter_map import ParameterMap, log_unit
from spflow.plugins.design.schemas import SPACE
from spflow.plugins.forward.parameters import PARAMETERS

_BY_NAME = {p.name: p for p in PARAMETERS}
_WHERE = "stage 'parameter_space'"


def _relative(name: str, relative: float) -> CalibratedParameter:
    spec = _BY_NAME[name]
    half = abs(spec.default) * relative
    lo, hi = max(spec.lower, spec.default - half), min(spec.upper, spec.default + half)
    if not lo < hi:
        raise ParameterError(f"{_WHERE}: ±{relative:g} around the default of {name} ({spec.default:g}) is the empty "
                             f"range [{lo:g}, {hi:g}]; give its range in 'ranges' (allowed {spec.describe_range()})")
    return calibrated_parameter(name, [lo, hi], f"{_WHERE} parameter 'ranges' {name!r}")


class ParameterSpace(Stage):
    name = "parameter_space"
    version = "4"  # 4: every unit in UDUNITS form (issue 23)
    description = "uniform bounds on calibrated parameters (UTCHEM names or labels of groups; explicit or ±relative)"
    output = SPACE
    params = {
        "names": Param(list, doc="design columns: UTCHEM names, or labels that 'ranges' defines"),
        "ranges": Param(dict, {}, doc="column -> [low, high] or {names, range, scale}; UTCHEM names not listed "
                                      "get ±relative around the default"),
        "relative": Param(float, 0.2, bounds=(0.0, 1.0), doc="half-width as a fraction of the default"),
    }

    def __init__(self, **params):
        super().__init__(**params)
        names, ranges = [str(n) for n in self.params["names"]], self.params["ranges"]
        if not names or len(set(names)) != len(names):
            raise ParameterError(f"{_WHERE} parameter 'names' must be a non-empty list without repeats")
        unknown = [n for n in list(names) + list(ranges) if n not in _BY_NAME and not isinstance(ranges.get(n), dict)]
        if unknown:
            raise ParameterError(f"{_WHERE}: unknown forward-model parameter {unknown[0]!r} (see `spflow list "
                                 "params`); a label of several parameters needs a table in 'ranges': "
                                 f"{unknown[0]} = {{names = [...], range = [low, high]}}")
        extra = sorted(set(ranges) - set(names))
        if extra:
            raise ParameterError(f"{_WHERE} parameter 'ranges' has {extra}, which are not in 'names' {names}")
        self._parameters = [calibrated_parameter(n, ranges[n], f"{_WHERE} parameter 'ranges' {n!r}") if n in ranges
                            else _relative(n, self.params["relative"]) for n in names]
        taken = [n for p in self._parameters for n in p.names]
        twice = sorted({n for n in taken if taken.count(n) > 1})
        if twice:
            raise ParameterError(f"{_WHERE}: {twice} set by more than one column; each UTCHEM name may be set by "
                                 "one column only")

    def run(self, ctx: StageContext) -> xr.Dataset:
        ps = self._parameters

        def column(p: CalibratedParameter, x: float) -> float:
            return float(np.log10(x)) if p.log else float(x)

        per = {UNITS_VARIABLE: "unit"}
        space = xr.Dataset(
            {
                "lower": ("param", [column(p, p.lower) for p in ps], per),
                "upper": ("param", [column(p, p.upper) for p in ps], per),
                "default": ("param", [column(p, min(max(p.default, p.lower), p.upper) if p.log else p.default)
                                      for p in ps], per),
                "unit": ("param", np.array([udunits(log_unit(p.unit) if p.log else p.unit) for p in ps])),
            },
            coords={"param": ("param", [p.label for p in ps], {"long_name": "calibrated parameter (design column)"})},
            attrs={"distribution": "independent uniform"},
        )
        return ParameterMap.of_parameters(ps).attach(space)
