"""The ``parameter_space`` stage: uniform bounds on chosen forward-model parameters.

Ranges are given explicitly (e.g. the thesis's Table 3.2) or as ``relative`` ± fraction around the calibrated
default (the thesis's ±20 % rule, Chapter 3.4), clipped to the parameter's physical bounds.
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from spflow.core.errors import ParameterError
from spflow.core.params import Param
from spflow.core.stage import Stage, StageContext
from spflow.plugins.design.schemas import SPACE
from spflow.plugins.forward.parameters import PARAMETERS

_BY_NAME = {p.name: p for p in PARAMETERS}


def _bounds(name: str, ranges: dict, relative: float) -> tuple[float, float]:
    spec = _BY_NAME[name]
    if name in ranges:
        pair = ranges[name]
        if not (isinstance(pair, (list, tuple)) and len(pair) == 2):
            raise ParameterError(f"stage 'parameter_space' parameter 'ranges': {name} must be [low, high], got {pair!r}")
        lo, hi = float(pair[0]), float(pair[1])
    else:
        half = abs(spec.default) * relative
        lo, hi = max(spec.lower, spec.default - half), min(spec.upper, spec.default + half)
    if not (spec.lower <= lo < hi <= spec.upper):
        raise ParameterError(
            f"stage 'parameter_space': range of {name} = [{lo:g}, {hi:g}] must satisfy low < high inside the "
            f"allowed range [{spec.lower:g}, {spec.upper:g}] {spec.unit}"
        )
    return lo, hi


class ParameterSpace(Stage):
    name = "parameter_space"
    description = "uniform bounds on forward-model parameters (explicit or ±relative around defaults)"
    output = SPACE
    params = {
        "names": Param(list, doc="forward-model parameter names (UTCHEM names)"),
        "ranges": Param(dict, {}, doc="name -> [low, high]; others get ±relative around the default"),
        "relative": Param(float, 0.2, bounds=(0.0, 1.0), doc="half-width as a fraction of the default"),
    }

    def __init__(self, **params):
        super().__init__(**params)
        names = self.params["names"]
        unknown = [n for n in list(names) + list(self.params["ranges"]) if n not in _BY_NAME]
        if unknown:
            raise ParameterError(f"stage 'parameter_space': unknown forward-model parameter {unknown[0]!r} "
                                 "(see `spflow list params`)")
        if not names or len(set(names)) != len(names):
            raise ParameterError("stage 'parameter_space' parameter 'names' must be a non-empty list without repeats")
        self._box = [_bounds(n, self.params["ranges"], self.params["relative"]) for n in names]

    def run(self, ctx: StageContext) -> xr.Dataset:
        names = list(self.params["names"])
        lower, upper = np.array(self._box).T
        return xr.Dataset(
            {
                "lower": ("param", lower, {"units": "per-parameter (see unit)"}),
                "upper": ("param", upper, {"units": "per-parameter (see unit)"}),
                "default": ("param", np.array([_BY_NAME[n].default for n in names]),
                            {"units": "per-parameter (see unit)"}),
                "unit": ("param", np.array([_BY_NAME[n].unit for n in names])),
            },
            coords={"param": names},
            attrs={"distribution": "independent uniform"},
        )
