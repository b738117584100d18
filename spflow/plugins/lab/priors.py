"""The ``priors`` stage: the lab fits' estimates turned into the parameter space of chapters 3-4 (uniform, as the
thesis, or truncated normal).

Thesis Algorithm 1 line 5 (and section 2.12): after the initial model calibration on the support experiments,
"consider +/-20 % uncertainty and uniform distribution on input parameter X". For every selected parameter the box is

* ``mode="relative"`` (default): ``estimate -/+ relative * |estimate|`` (the thesis rule with ``relative = 0.2``);
* ``mode="fit_uncertainty"``: ``estimate -/+ k * std``, the fit's own standard error,

clipped to the parameter's physical bounds (``spflow list params``). Parameters no lab test measures (e.g. the Corey
exponents of Table 3.2) can be added with explicit ``ranges``.

``distribution="uniform"`` (default) makes every parameter uniform on its box, as the thesis. With
``distribution="truncated_normal"`` each fitted parameter is N(estimate, std²) of its fit truncated to the box (the
priors "as the lab fit produced them"), recorded in the space's ``distribution`` / ``distribution_parameters``
variables (:func:`spflow.plugins.surrogates.input_marginals.marginal_variables`); parameters from ``ranges`` stay
uniform. The surrogate stages fit under these marginals (docs/surrogates.md, Input distributions), ``lhs_design``
and the screening stages draw from them, the MCMC samplers take them as the prior and ``nsga2_calibration`` searches
their supports, the box (docs/calibration.md, "Search space"). The output is the SPACE dataset of
:mod:`spflow.plugins.design.schemas` -- the same contract as ``parameter_space`` -- with ``default`` = the lab
estimate, so it feeds ``lhs_design``, ``sobol_screening``, ``pce``, ``nsga2_calibration`` and the MCMC samplers
unchanged.
"""

from __future__ import annotations

import difflib

import numpy as np
import xarray as xr

from spflow.core.cf_metadata import UNITS_VARIABLE, udunits
from spflow.core.errors import ParameterError
from spflow.core.params import Param
from spflow.core.stage import Stage, StageContext
from spflow.plugins.design.schemas import SPACE
from spflow.plugins.forward.parameters import PARAMETERS, resolve_params
from spflow.plugins.lab.fit_result import FIT
from spflow.plugins.surrogates.input_marginals import TruncatedNormal, Uniform, marginal_variables

__all__ = ["FIT_PORTS", "Priors", "prior_box"]

_BY_NAME = {p.name: p for p in PARAMETERS}
#: optional input ports, one per support experiment (named after the fit stages; adsorption has one port per
#: component because ``fit_adsorption`` fits either). Any FIT dataset may be wired to any port.
FIT_PORTS = ("fit_polymer_rheology", "fit_polymer_coreflood", "fit_polymer_adsorption", "fit_surfactant_adsorption",
             "fit_tracer", "fit_phase_behaviour", "fit_ift", "fit_me_viscosity", "fit_desaturation")


def _unknown(name: str, where: str) -> ParameterError:
    close = difflib.get_close_matches(str(name).upper(), list(_BY_NAME), n=3, cutoff=0.6)
    hint = f"; did you mean {', '.join(close)}?" if close else "; `spflow list params` lists all parameters"
    return ParameterError(f"{where}: unknown forward-model parameter {name!r}{hint}")


def prior_box(name: str, estimate: float, std: float, *, mode: str, relative: float, k: float) -> tuple[float, float]:
    """Uniform prior bounds of ``name`` around a fitted ``estimate`` (see the module docstring), clipped to the
    parameter's physical bounds; ``ParameterError`` for an empty box or an estimate outside the bounds."""
    spec = _BY_NAME[name]
    where = f"stage 'priors': {name}"
    if not (np.isfinite(estimate) and spec.lower <= estimate <= spec.upper):
        raise ParameterError(f"{where}: fitted estimate {estimate!r} is outside the allowed range "
                             f"{spec.describe_range()}")
    if mode == "relative":
        half = relative * abs(estimate)
        if not half > 0.0:
            raise ParameterError(f"{where}: estimate {estimate!r} gives an empty ±{relative:g} box; use "
                                 "mode='fit_uncertainty' or give explicit 'ranges' for it")
    else:
        if not (np.isfinite(std) and std > 0.0):
            raise ParameterError(f"{where}: fit standard error {std!r} must be finite and > 0 for "
                                 "mode='fit_uncertainty'")
        half = k * std
    lo, hi = max(spec.lower, estimate - half), min(spec.upper, estimate + half)
    if not lo < hi:
        raise ParameterError(f"{where}: prior box [{lo:g}, {hi:g}] is empty inside the allowed range "
                             f"{spec.describe_range()}")
    return lo, hi


class Priors(Stage):
    name = "priors"
    # 3: distribution="truncated_normal"; the marginals recorded in the space (issue #24); 4: every unit in UDUNITS
    # form (issue 23)
    version = "4"
    description = ("priors around lab-fit estimates (±20 % rule of Algorithm 1, or k fit standard errors), uniform "
                   "or truncated normal")
    inputs = {port: FIT for port in FIT_PORTS}
    optional_inputs = frozenset(FIT_PORTS)
    output = SPACE
    params = {
        "names": Param(list, doc="parameters of the space (UTCHEM names): estimated by a wired fit or in 'ranges'"),
        "mode": Param(str, "relative", choices=("relative", "fit_uncertainty"),
                      doc="box half-width: relative*|estimate| or k*std of the fit"),
        "relative": Param(float, 0.2, bounds=(0.0, 1.0), doc="half-width as a fraction of the estimate (thesis 0.2)"),
        "k": Param(float, 2.0, bounds=(0.0, None), doc="half-width in fit standard errors (mode fit_uncertainty)"),
        "ranges": Param(dict, {}, doc="name -> [low, high] for parameters no wired fit estimates"),
        "distribution": Param(str, "uniform", choices=("uniform", "truncated_normal"),
                              doc="law on the box: uniform (thesis), or N(estimate, std^2) of the fit truncated to "
                                  "the box (parameters from 'ranges' stay uniform)"),
    }

    def __init__(self, **params):
        super().__init__(**params)
        names, ranges = self.params["names"], self.params["ranges"]
        for name in list(names) + list(ranges):
            if name not in _BY_NAME:
                raise _unknown(name, "stage 'priors'")
        if not names or len(set(names)) != len(names):
            raise ParameterError("stage 'priors' parameter 'names' must be a non-empty list without repeats")
        if not (self.params["relative"] > 0.0 and self.params["k"] > 0.0):
            raise ParameterError("stage 'priors' parameters 'relative' and 'k' must be > 0")
        self._ranges = {}
        for name, pair in ranges.items():
            spec = _BY_NAME[name]
            if not (isinstance(pair, (list, tuple)) and len(pair) == 2):
                raise ParameterError(f"stage 'priors' parameter 'ranges': {name} must be [low, high], got {pair!r}")
            lo, hi = float(pair[0]), float(pair[1])
            if not spec.lower <= lo < hi <= spec.upper:
                raise ParameterError(f"stage 'priors' parameter 'ranges': {name} = [{lo:g}, {hi:g}] must satisfy "
                                     f"low < high inside the allowed range {spec.describe_range()}")
            self._ranges[name] = (lo, hi)
        extra = sorted(set(ranges) - set(names))
        if extra:
            raise ParameterError(f"stage 'priors' parameter 'ranges': {extra[0]!r} is not in 'names' {list(names)}")

    def _estimates(self, fits: dict[str, xr.Dataset]) -> dict[str, tuple[float, float, str]]:
        """``name -> (estimate, std, source port)`` of the selected names that no explicit range covers."""
        found: dict[str, tuple[float, float, str]] = {}
        wanted = set(self.params["names"]) - set(self._ranges)
        for port, fit in fits.items():
            for name, est, std in zip(fit["param"].values, fit["estimate"].values, fit["std"].values):
                name = str(name)
                if name not in wanted:
                    continue
                if name in found:
                    raise ParameterError(f"stage 'priors': {name} is estimated by both {found[name][2]!r} and "
                                         f"{port!r}; wire only one of them or give {name} explicit 'ranges'")
                found[name] = (float(est), float(std), port)
        missing = sorted(wanted - set(found))
        if missing:
            fitted = sorted({str(n) for fit in fits.values() for n in fit["param"].values})
            raise ParameterError(f"stage 'priors': no wired fit estimates {missing[0]!r} (fitted: {fitted}); "
                                 "wire the fit that measures it or give it explicit 'ranges'")
        return found

    def run(self, ctx: StageContext, **fits: xr.Dataset) -> xr.Dataset:
        if not fits and set(self.params["names"]) - set(self._ranges):
            raise ParameterError(f"stage 'priors': wire at least one lab fit to its input ports {list(FIT_PORTS)}")
        found = self._estimates(fits)
        names = list(self.params["names"])
        p = self.params
        rows, source, marginals = [], [], []
        for name in names:
            if name in self._ranges:
                lo, hi = self._ranges[name]
                rows.append((lo, hi, _BY_NAME[name].default))
                source.append("ranges")
                marginals.append(Uniform(lo, hi))
            else:
                est, std, port = found[name]
                lo, hi = prior_box(name, est, std, mode=p["mode"], relative=p["relative"], k=p["k"])
                rows.append((lo, hi, est))
                source.append(port)
                marginals.append(_marginal(name, est, std, lo, hi, p["distribution"], port))
        lower, upper, centre = (np.array(c) for c in zip(*rows))
        _check_feasible(dict(zip(names, lower)), dict(zip(names, upper)))
        laws = {} if p["distribution"] == "uniform" else marginal_variables(marginals)
        return xr.Dataset(
            {
                **laws,
                "lower": ("param", lower, {UNITS_VARIABLE: "unit"}),
                "upper": ("param", upper, {UNITS_VARIABLE: "unit"}),
                "default": ("param", centre, {UNITS_VARIABLE: "unit",
                                              "long_name": "lab estimate (forward default for explicit ranges)"}),
                "unit": ("param", np.array([udunits(_BY_NAME[n].unit) for n in names])),
                "source": ("param", np.array(source)),
            },
            coords={"param": ("param", names, {"long_name": "forward-model parameter"})},
            attrs={"distribution": "independent uniform" if p["distribution"] == "uniform" else
                   "independent, per parameter in the variable 'distribution'", "mode": p["mode"],
                   "half_width": f"{p['relative']:g} * |estimate|" if p["mode"] == "relative"
                   else f"{p['k']:g} * std"},
        )


def _marginal(name: str, estimate: float, std: float, lower: float, upper: float, distribution: str, port: str):
    """The prior law of a fitted parameter on its box [lower, upper]: uniform, or N(estimate, std²) truncated to it."""
    if distribution == "uniform":
        return Uniform(lower, upper)
    if not (np.isfinite(std) and std > 0.0):
        raise ParameterError(f"stage 'priors': {name}: the fit standard error from {port!r} is {std!r}; "
                             "distribution='truncated_normal' needs it finite and > 0 (use distribution='uniform' "
                             "or give it explicit 'ranges')")
    return TruncatedNormal(estimate, std, lower, upper)


def _check_feasible(lower: dict[str, float], upper: dict[str, float]) -> None:
    """Every point of the box must be a valid forward-model parameter set: the cross-parameter rules of
    :func:`~spflow.plugins.forward.parameters.resolve_params` (``CSEL < CSEU``, high-Nc residual <= low-Nc residual,
    residual sums < 1, ...) are monotone in each parameter, so checking the all-upper corner and, for each ordered
    pair, the corner with the larger-side parameter low (everything else high) covers the box; parameters outside the
    box keep their defaults."""
    corners = [dict(upper)]
    for small, large in (("CSEL", "CSEU"), ("S1RC", "S1RWC"), ("S2RC", "S2RWC"), ("S3RC", "S3RWC")):
        if large in lower:
            corners.append({**upper, large: lower[large]})
    for corner in corners:
        try:
            resolve_params(corner)
        except ParameterError as exc:
            raise ParameterError(f"stage 'priors': the prior box contains invalid forward-model parameter sets "
                                 f"({exc}); narrow 'relative'/'k' or give explicit 'ranges'") from None
