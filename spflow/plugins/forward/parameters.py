"""The forward model's parameter catalogue: UTCHEM names, units, defaults, physical bounds and sub-models.

Defaults are the thesis's calibrated set (Table 2.4) with the fluid data of Table 2.1 and the core data of
Tables 2.2-2.3; where the thesis is silent a Berea-typical value is chosen. Each choice and its source is listed in
``docs/forward_model.md``. Bounds are physical limits, wide enough to contain the prior ranges of Tables 3.1, 3.2
and 4.1. Dispersivities are in ft, the thesis's unit (Fig. 2.9). The fluid viscosities are bounded by what
brines (``VIS1`` 0.1-10 cP: IAPWS water, chloride brines) and liquid oils (``VIS2`` >= 0.1 cP) reach; sources in
the same file.

``resolve_params`` merges user values with the defaults and validates them before any work: unknown names (with
close-match suggestions), non-numbers (strings are not coerced), NaN/inf, values outside their bounds and
cross-parameter violations (among them ``SWI`` below ``S1RWC``) raise :class:`spflow.core.errors.ParameterError` (a
``ValueError``) naming the parameter and its allowed range.
"""

from __future__ import annotations

import difflib
import math
from collections.abc import Mapping
from dataclasses import dataclass

from spflow.core.errors import ParameterError

__all__ = ["ParameterSpec", "PARAMETERS", "resolve_params", "parameter_table", "default_params"]


@dataclass(frozen=True)
class ParameterSpec:
    """One forward-model parameter (``lower``/``upper`` inclusive; ``integer`` for flags)."""

    name: str
    unit: str
    default: float
    lower: float
    upper: float
    submodel: str
    description: str
    integer: bool = False

    def describe_range(self) -> str:
        unit = f" {self.unit}" if self.unit and self.unit != "-" else ""
        if self.integer:
            return f"integer in [{self.lower:g}, {self.upper:g}]{unit}"
        return f"[{self.lower:g}, {self.upper:g}]{unit}"


def _p(name, unit, default, lower, upper, submodel, description, integer=False):
    return ParameterSpec(name, unit, float(default), float(lower), float(upper), submodel, description, integer)


_CORE = "core and injection"
_FLUID = "fluids"
_PVIS = "polymer viscosity (Eqs. 2.1-2.5)"
_PRK = "permeability reduction (Eqs. 2.6-2.8)"
_IPV = "inaccessible pore volume"
_PB = "phase behaviour (Hand's rule)"
_IFT = "IFT (Eqs. 2.9-2.10)"
_MEV = "microemulsion viscosity (Eq. 2.11)"
_CDC = "capillary desaturation (Eqs. 2.12-2.13)"
_KR = "relative permeability (Eq. 2.14)"
_ADS = "adsorption (Eqs. 2.15-2.16)"
_DISP = "dispersion (Eq. 1.9)"
_PC = "capillary pressure (Eq. 1.8)"

#: Every parameter of the forward model, in catalogue order.
PARAMETERS: tuple[ParameterSpec, ...] = (
    # --- core and injection (thesis silent on the BCF cores: Table 2.2/2.3 support cores used) ---
    _p("LENGTH", "m", 0.1524, 0.01, 10.0, _CORE, "core length (6 in, Tables 2.2-2.3 support cores)"),
    _p("DIAMETER", "m", 0.0508, 0.005, 1.0, _CORE, "core diameter (2 in, Tables 2.2-2.3)"),
    _p("PORO", "-", 0.23, 0.01, 0.6, _CORE, "porosity (Table 2.3 Berea core)"),
    _p("PERM", "mD", 700.0, 0.1, 1.0e5, _CORE, "absolute permeability (Table 2.3 Berea core)"),
    _p("QINJ", "ml/min", 0.25, 1.0e-4, 1.0e3, _CORE, "constant injection rate (Table 2.2)"),
    _p("SWI", "-", 0.2, 0.0, 1.0, _CORE, "initial water saturation (Berea-typical; = S1RWC)"),
    _p("C50", "meq/ml", 0.145, 0.0, 5.0, _CORE, "initial anion concentration of the connate brine (Table 2.1)"),
    _p("C60", "meq/ml", 0.0097, 0.0, 5.0, _CORE, "initial divalent-cation concentration (Table 2.1)"),
    # --- fluids ---
    _p("VIS1", "cP", 1.0, 0.1, 10.0, _FLUID, "water (brine) viscosity (Table 2.1)"),
    _p("VIS2", "cP", 13.8, 0.1, 1.0e5, _FLUID, "oil viscosity (Table 2.1)"),
    _p("XIFTW", "log10(dyne/cm)", 1.32, -3.0, 2.5, _IFT, "log10 of the oil-water IFT (Table 2.4)"),
    # --- polymer viscosity ---
    _p("AP1", "(wt%)^-1", 15.0, 0.0, 1.0e4, _PVIS, "Flory-Huggins coefficient of Cp (Table 2.4)"),
    _p("AP2", "(wt%)^-2", 0.0, 0.0, 1.0e5, _PVIS, "Flory-Huggins coefficient of Cp^2 (Table 2.4)"),
    _p("AP3", "(wt%)^-3", 155.0, 0.0, 1.0e6, _PVIS, "Flory-Huggins coefficient of Cp^3 (Table 2.4)"),
    _p("BETAP", "-", 1.0, 0.0, 100.0, _PVIS, "divalent weight in the polymer effective salinity (Table 2.4)"),
    _p("CSE1", "meq/ml", 1.0e-4, 1.0e-8, 10.0, _PVIS, "salinity floor of C_SEP (Table 2.4)"),
    _p("SSLOPE", "-", -0.76, -5.0, 5.0, _PVIS, "log-log slope of viscosity vs C_SEP (Table 2.4)"),
    _p("GAMMAC", "day*darcy^(1/2)/(ft*s)", 40.0, 0.0, 1.0e4, _PVIS, "in-situ shear-rate coefficient (Table 2.4)"),
    _p("GAMHF", "1/s", 60.0, 1.0e-3, 1.0e6, _PVIS, "half-viscosity shear rate (Tables 3.2/4.1 ranges)"),
    _p("POWN", "-", 1.66, 1.0, 5.0, _PVIS, "Meter exponent P_alpha (Table 2.4)"),
    _p("IGAMHF", "-", 0, 0, 1, _PVIS, "0: GAMHF fixed; 1: half shear rate from Eq. 2.5 (A0, A1, A2)", True),
    _p("A0", "1/s", -588.0, -1.0e5, 1.0e5, _PVIS, "Eq. 2.5 intercept a0 (Table 2.4)"),
    _p("A1", "(1/s)/(meq/ml)", 7683.0, -1.0e6, 1.0e6, _PVIS, "Eq. 2.5 salinity slope a1 (Table 2.4)"),
    _p("A2", "(wt%)^-1", -12.0, -1.0e3, 1.0e3, _PVIS, "Eq. 2.5 concentration exponent a2 (Table 2.4)"),
    # --- permeability reduction ---
    _p("BRK", "1/wt%", 100.0, 0.0, 1.0e5, _PRK, "permeability-reduction parameter b_rk (Table 2.4)"),
    # c_rk's unit from Eq. 2.8: 1 - c_rk (AP1 C_SEP^SSLOPE)^(1/3) / (sqrt(k_x k_y)/phi)^(1/2) is a number, with
    # AP1 in 1/wt% (C_SEP^SSLOPE a number: C_SEP in meq/ml taken as a number, as in Eq. 2.1) and k in darcy, so
    # c_rk = [darcy^(1/2)] / [(wt%)^(-1/3)] = darcy^(1/2) (wt%)^(1/3): a length, written in UDUNITS as the scaled
    # metre cf_metadata.CRK_UNIT (docs/forward_model.md, "Units").
    _p("CRK", "darcy^(1/2)*(wt%)^(1/3)", 0.068, 0.0, 1.0, _PRK, "permeability-reduction parameter c_rk (Table 2.4)"),
    _p("RKCAP", "-", 10.0, 1.0, 1.0e3, _PRK, "cap of R_k,max (Eq. 2.8)"),
    # --- inaccessible pore volume ---
    _p("EPHI3", "-", 1.0, 0.1, 1.0, _IPV, "surfactant-accessible porosity fraction (thesis silent: no IPV)"),
    _p("EPHI4", "-", 0.85, 0.1, 1.0, _IPV, "polymer-accessible porosity fraction (Table 2.4)"),
    # --- phase behaviour ---
    _p("C2PLC", "-", 0.0, 0.0, 0.0, _PB, "oil fraction at the type II(+) plait point (Table 2.4; only the apex)"),
    _p("C2PRC", "-", 1.0, 1.0, 1.0, _PB, "oil fraction at the type II(-) plait point (Table 2.4; only the apex)"),
    _p("EPSME", "vol. frac.", 1.0e-4, 0.0, 0.1, _PB, "critical micelle concentration (Table 2.4)"),
    _p("CSEL", "meq/ml", 0.255, 1.0e-3, 10.0, _PB, "lower effective-salinity limit of type III (Table 2.4)"),
    _p("CSEU", "meq/ml", 0.305, 1.0e-3, 10.0, _PB, "upper effective-salinity limit of type III (Table 2.4)"),
    _p("HBNC70", "vol. frac.", 0.027, 1.0e-3, 0.5, _PB, "binodal height at zero salinity C33max0 (Table 2.4)"),
    _p("HBNC71", "vol. frac.", 0.0155, 1.0e-3, 0.5, _PB, "binodal height at optimal salinity C33max1 (Table 2.4)"),
    _p("HBNC72", "vol. frac.", 0.02, 1.0e-3, 0.5, _PB, "binodal height at twice optimal salinity C33max2 (Table 2.4)"),
    _p("BETA6", "-", 0.8, 0.0, 10.0, _PB, "divalent slope of the phase-behaviour effective salinity"),
    _p("F6S", "-", 0.0, 0.0, 1.0, _PB, "fraction of divalent cations bound to micelles (no exchange model: 0)"),
    # --- IFT ---
    _p("CHUH", "-", 0.3, 0.01, 10.0, _IFT, "Chun-Huh constant c (Table 2.4)"),
    _p("AHUH", "-", 10.0, 0.1, 100.0, _IFT, "Chun-Huh constant a (Table 2.4)"),
    # --- microemulsion viscosity ---
    _p("ALPHAV1", "-", 2.0, 0.0, 20.0, _MEV, "ME viscosity parameter alpha_V1 (Table 2.4)"),
    _p("ALPHAV2", "-", 2.0, 0.0, 20.0, _MEV, "ME viscosity parameter alpha_V2 (Table 2.4)"),
    _p("ALPHAV3", "cP", 0.0, 0.0, 20.0, _MEV, "ME viscosity parameter alpha_V3 (Table 2.4)"),
    _p("ALPHAV4", "-", 0.9, 0.0, 20.0, _MEV, "ME viscosity parameter alpha_V4 (Table 2.4)"),
    _p("ALPHAV5", "-", 0.7, 0.0, 20.0, _MEV, "ME viscosity parameter alpha_V5 (Table 2.4)"),
    # --- capillary desaturation ---
    _p("T11", "-", 1500.0, 0.0, 1.0e7, _CDC, "trapping parameter of the aqueous phase (Table 2.4)"),
    _p("T22", "-", 1100.0, 0.0, 1.0e7, _CDC, "trapping parameter of the oleic phase (Table 2.4)"),
    _p("T33", "-", 346.0, 0.0, 1.0e7, _CDC, "trapping parameter of the microemulsion (Table 2.4)"),
    # --- relative permeability: low capillary number (Berea-typical) ---
    _p("S1RWC", "-", 0.2, 0.0, 0.9, _KR, "aqueous residual saturation, low Nc"),
    _p("S2RWC", "-", 0.3, 0.0, 0.9, _KR, "oleic residual saturation, low Nc"),
    _p("S3RWC", "-", 0.2, 0.0, 0.9, _KR, "microemulsion residual saturation, low Nc"),
    _p("P1RWC", "-", 0.1, 1.0e-3, 1.0, _KR, "aqueous end-point rel-perm, low Nc (thesis sec. 1.8: M = 2.5)"),
    _p("P2RWC", "-", 0.8, 1.0e-3, 1.0, _KR, "oleic end-point rel-perm, low Nc (thesis sec. 1.8: M = 2.5)"),
    _p("P3RWC", "-", 0.1, 1.0e-3, 1.0, _KR, "microemulsion end-point rel-perm, low Nc"),
    _p("E1WC", "-", 2.0, 1.0, 6.0, _KR, "aqueous Corey exponent, low Nc (Table 3.2 range 1.5-3)"),
    _p("E2WC", "-", 2.0, 1.0, 6.0, _KR, "oleic Corey exponent, low Nc"),
    _p("E3WC", "-", 2.0, 1.0, 6.0, _KR, "microemulsion Corey exponent, low Nc"),
    # --- relative permeability: high capillary number ---
    _p("S1RC", "-", 0.0, 0.0, 0.9, _KR, "aqueous residual saturation, high Nc"),
    _p("S2RC", "-", 0.0, 0.0, 0.9, _KR, "oleic residual saturation, high Nc"),
    _p("S3RC", "-", 0.0, 0.0, 0.9, _KR, "microemulsion residual saturation, high Nc"),
    _p("P1RC", "-", 1.0, 1.0e-3, 1.0, _KR, "aqueous end-point rel-perm, high Nc"),
    _p("P2RC", "-", 1.0, 1.0e-3, 1.0, _KR, "oleic end-point rel-perm, high Nc"),
    _p("P3RC", "-", 1.0, 1.0e-3, 1.0, _KR, "microemulsion end-point rel-perm, high Nc"),
    _p("E1C", "-", 2.0, 1.0, 6.0, _KR, "aqueous Corey exponent, high Nc (Table 2.4)"),
    _p("E2C", "-", 2.0, 1.0, 6.0, _KR, "oleic Corey exponent, high Nc (Table 2.4)"),
    _p("E3C", "-", 2.0, 1.0, 6.0, _KR, "microemulsion Corey exponent, high Nc (Table 2.4)"),
    # --- adsorption ---
    _p("AD31", "-", 0.31, 0.0, 10.0, _ADS, "surfactant Langmuir a31 (Table 2.4)"),
    _p("AD32", "ml/meq", 0.0, 0.0, 100.0, _ADS, "surfactant Langmuir salinity slope a32 (Table 2.4)"),
    _p("B3D", "1/vol. frac.", 100.0, 0.0, 1.0e5, _ADS, "surfactant Langmuir b3 (Table 2.4)"),
    _p("AD41", "-", 8.4, 0.0, 100.0, _ADS, "polymer Langmuir a41 (Table 2.4)"),
    _p("AD42", "ml/meq", 0.0, 0.0, 100.0, _ADS, "polymer Langmuir salinity slope a42 (Table 2.4)"),
    _p("B4D", "1/wt%", 100.0, 0.0, 1.0e5, _ADS, "polymer Langmuir b4 (Table 2.4)"),
    _p("ADSREV4", "-", 0.0, 0.0, 1.0, _ADS, "reversible fraction of the polymer adsorption: 0 irreversible in "
       "concentration (UTCHEM), 1 fully reversible (ECLIPSE PLYROCK adsorption index 1)"),
    _p("KADS", "1/s", 1.0e-3, 1.0e-7, 1.0, _ADS, "first-order rate of kinetic adsorption (effect kinetic_adsorption)"),
    # --- dispersion ---
    _p("ALPHAL1", "ft", 0.01, 0.0, 1.0, _DISP, "longitudinal dispersivity of the aqueous phase (Fig. 2.9)"),
    _p("ALPHAL2", "ft", 0.01, 0.0, 1.0, _DISP, "longitudinal dispersivity of the oleic phase (Fig. 2.9)"),
    _p("ALPHAL3", "ft", 0.01, 0.0, 1.0, _DISP, "longitudinal dispersivity of the microemulsion (Fig. 2.9)"),
    _p("DMOL", "m^2/s", 0.0, 0.0, 1.0e-6, _DISP, "molecular diffusion coefficient / tortuosity (thesis silent: 0)"),
    # --- capillary pressure (effect capillary_pressure, off by default) ---
    _p("CPC0", "Pa", 5000.0, 0.0, 1.0e6, _PC, "Brooks-Corey entry pressure p_c,0 at the oil-water IFT"),
    _p("EPC0", "-", 2.0, 0.2, 10.0, _PC, "Brooks-Corey pore-size index lambda_b"),
)

_BY_NAME = {spec.name: spec for spec in PARAMETERS}

#: (lower, higher) pairs whose values must satisfy value(lower) < value(higher).
_STRICT_ORDER = (("CSEL", "CSEU"),)
#: high-Nc residual <= low-Nc residual, per phase.
_RESIDUAL_ORDER = (("S1RC", "S1RWC"), ("S2RC", "S2RWC"), ("S3RC", "S3RWC"))


def default_params() -> dict[str, float]:
    """All defaults, ``{name: value}``."""
    return {spec.name: spec.default for spec in PARAMETERS}


def _unknown(name: str) -> ParameterError:
    close = difflib.get_close_matches(name.upper(), list(_BY_NAME), n=3, cutoff=0.6)
    hint = f"; did you mean {', '.join(close)}?" if close else "; `spflow list params` lists all parameters"
    return ParameterError(f"unknown forward-model parameter {name!r}{hint}")


def _check_value(spec: ParameterSpec, value) -> float:
    if isinstance(value, (bool, str, bytes)):  # a string is not coerced: "0.5" is a typing slip, not a number
        raise ParameterError(f"parameter {spec.name} must be a number, got {value!r}; allowed {spec.describe_range()}")
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise ParameterError(
            f"parameter {spec.name} must be a number, got {value!r}; allowed {spec.describe_range()}"
        ) from None
    if not math.isfinite(x):
        raise ParameterError(f"parameter {spec.name} is {x!r} (must be finite); allowed {spec.describe_range()}")
    if not spec.lower <= x <= spec.upper:
        raise ParameterError(f"parameter {spec.name} = {x!r} is out of range; allowed {spec.describe_range()}")
    if spec.integer and not x.is_integer():
        raise ParameterError(f"parameter {spec.name} = {x!r} must be an integer; allowed {spec.describe_range()}")
    return x


def _check_cross(p: dict[str, float]) -> None:
    for lo, hi in _STRICT_ORDER:
        if not p[lo] < p[hi]:
            raise ParameterError(f"parameters {lo} = {p[lo]!r} and {hi} = {p[hi]!r} must satisfy {lo} < {hi}")
    for high_nc, low_nc in _RESIDUAL_ORDER:
        if p[high_nc] > p[low_nc]:
            raise ParameterError(
                f"parameter {high_nc} = {p[high_nc]!r} (high-Nc residual) must not exceed {low_nc} = {p[low_nc]!r}; "
                f"allowed range [0, {p[low_nc]!r}]"
            )
    for names in (("S1RWC", "S2RWC", "S3RWC"), ("S1RC", "S2RC", "S3RC")):
        total = sum(p[n] for n in names)
        if not total < 1.0:
            raise ParameterError(f"residual saturations {'+'.join(names)} = {total!r} must sum to < 1")
    if p["SWI"] < p["S1RWC"]:
        raise ParameterError(f"parameter SWI = {p['SWI']!r} (initial water saturation) is below S1RWC = "
                             f"{p['S1RWC']!r} (residual water saturation); allowed SWI in [S1RWC, 1] = "
                             f"[{p['S1RWC']!r}, 1]")
    if not p["BETA6"] * p["F6S"] < 1.0:
        raise ParameterError(f"BETA6*F6S = {p['BETA6'] * p['F6S']!r} must be < 1 (effective salinity denominator)")


def resolve_params(params: Mapping | None) -> dict[str, float]:
    """Defaults overridden by ``params``; every value validated (see module docstring). Returns a new dict."""
    if params is not None and not isinstance(params, Mapping):
        raise ParameterError(f"params must be a mapping of parameter name -> number, got {type(params).__name__}")
    resolved = default_params()
    for name, value in (params or {}).items():
        if not isinstance(name, str) or name not in _BY_NAME:
            raise _unknown(str(name))
        resolved[name] = _check_value(_BY_NAME[name], value)
    _check_cross(resolved)
    return resolved


def parameter_table() -> list[dict]:
    """One dict per parameter (name, unit, default, lower, upper, submodel, description) for ``spflow list params``."""
    return [
        {
            "name": s.name,
            "unit": s.unit,
            "default": s.default,
            "lower": s.lower,
            "upper": s.upper,
            "submodel": s.submodel,
            "description": s.description,
        }
        for s in PARAMETERS
    ]
