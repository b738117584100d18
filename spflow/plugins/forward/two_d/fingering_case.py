"""The viscous-fingering case of thesis sec. 1.8 (Fig. 1.9): heterogeneous core, water flood with and without
0.25 wt % polymer.

Thesis data: phi = 0.21, initial S_w = 0.30, mu_o / mu_w = 20, end-point mobility ratio
``M = (k_rw^0 / mu_w) / (k_ro^0 / mu_o) = 2.5`` without polymer and 0.5 with 0.25 wt % polymer, polymer viscosity a
function of concentration only (Eq. 2.1, no salinity or shear effect), log-k variance 0.1 and correlation lengths
0.1 of the domain, 400 x 80 cells. Choices where the thesis is silent: the catalogue's low-Nc Corey curves
(``k_rw^0 = 0.1``, ``k_ro^0 = 0.8``, exponents 2: ``M = 0.1 * 20 / 0.8 = 2.5``) with the residual water saturation
equal to the initial 0.30 (no mobile connate water); AP1 set so that Eq. 2.1 gives ``M = 0.5`` at 0.25 wt % with the
catalogue's AP3 (AP2 = 0); no polymer adsorption, IPV or permeability reduction (the thesis names viscosity as the
only polymer effect of this case).
"""

from __future__ import annotations

from .. import units
from ..parameters import default_params

__all__ = ["POLYMER_WT_PERCENT", "end_point_mobility_ratio", "fingering_params", "fingering_effects",
           "fingering_schedule"]

POLYMER_WT_PERCENT = 0.25
MOBILITY_RATIO_WATER = 2.5
MOBILITY_RATIO_POLYMER = 0.5
VISCOSITY_RATIO = 20.0


def fingering_params() -> dict[str, float]:
    """Parameters of the case (see the module docstring); AP1 from Eq. 2.1 for ``M = 0.5`` at 0.25 wt %."""
    d = default_params()
    mu_w = d["VIS1"]
    mu_o = VISCOSITY_RATIO * mu_w
    krw, kro = d["P1RWC"], d["P2RWC"]
    mu_p = krw * mu_o / (MOBILITY_RATIO_POLYMER * kro)  # polymer-solution viscosity for M = 0.5
    c = POLYMER_WT_PERCENT
    ap3 = d["AP3"]
    ap1 = (mu_p / mu_w - 1.0 - ap3 * c**3) / c
    return {"PORO": 0.21, "SWI": 0.30, "S1RWC": 0.30, "VIS2": mu_o, "AP1": ap1, "AP2": 0.0, "AP3": ap3}


def end_point_mobility_ratio(params: dict[str, float], polymer: bool) -> float:
    """``M = (k_rw^0 / mu_displacing) / (k_ro^0 / mu_o)`` with the Eq. 2.1 viscosity at 0.25 wt % for polymer."""
    d = {**default_params(), **params}
    c = POLYMER_WT_PERCENT
    mu = d["VIS1"] * (1.0 + (d["AP1"] + (d["AP2"] + d["AP3"] * c) * c) * c) if polymer else d["VIS1"]
    return (d["P1RWC"] / mu) / (d["P2RWC"] / d["VIS2"])


def fingering_effects() -> dict[str, float]:
    """Polymer viscosity by concentration only: no shear thinning, salinity dependence, adsorption, IPV or R_k."""
    return {"shear_thinning": 0.0, "polymer_salinity": 0.0, "polymer_adsorption": 0.0,
            "inaccessible_pore_volume": 0.0, "permeability_reduction": 0.0}


def fingering_schedule(polymer: bool, pv: float = 1.0) -> list[dict]:
    """Continuous injection of brine (at the initial 9400 ppm) with or without 0.25 wt % polymer."""
    ppm = units.wt_percent_to_polymer_ppm(POLYMER_WT_PERCENT) if polymer else 0.0
    return [{"pv": pv, "salinity_ppm": 9400.0, "polymer_ppm": ppm, "name": "polymer" if polymer else "water"}]
