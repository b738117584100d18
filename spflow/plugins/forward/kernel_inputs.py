"""Flat float64 parameter vector for the compiled kernel, and its index layout.

The kernel cannot take dicts, so the resolved parameters (``parameters.resolve_params``) and effect strengths
(``effects.EffectRegistry.resolve``) are packed here into one array, converted to kernel units (SI for lengths,
permeability, velocity and time; cP for viscosity, mN/m for IFT; UTCHEM units for concentrations). Built-in effects
are applied here as parameter scalings (adsorption capacity, IPV, dispersivity, trapping parameters, Pc entry
pressure, salinity exponent, kinetic rate, reversible adsorption fraction) or passed as strength scalars (shear thinning, permeability reduction).
The index constants are module-level integers, which numba freezes as compile-time constants.
"""

from __future__ import annotations

import math

import numpy as np

from . import units

# --- core, flow, fluids ---
PHI, PERM_M2, PERM_D, UT, LENGTH, T_PV, SWI, C50, C60, VIS1, VIS2, SIGOW = range(12)
# --- polymer ---
AP1, AP2, AP3, BETAP, CSE1, SSLOPE, GAMMAC, GAMHF, POWN, IGAMHF, A0, A1, A2, S_SHEAR, BRK, CRK, RKCAP, S_RK = range(
    12, 30
)
EPHI3, EPHI4 = 30, 31
# --- phase behaviour, IFT, ME viscosity ---
EPSME, CSEL, CSEU, HB0, HB1, HB2, BETA6, F6S, CHUH, AHUH, AV1, AV2, AV3, AV4, AV5 = range(32, 47)
# --- trapping / relative permeability: index + 3*l-1 for phase l (1..3) ---
T1 = 47  # T11, T22, T33 (scaled by the capillary_desaturation strength)
CDC = 50  # 1.0 if capillary desaturation is on
SR_LOW, KR_LOW, N_LOW, SR_HIGH, KR_HIGH, N_HIGH = 51, 54, 57, 60, 63, 66
# --- adsorption ---
AD31, AD32, B3D, AD41, AD42, B4D, KADS = range(69, 76)
# --- dispersion (PV units: alpha_l / L) and diffusion, capillary pressure ---
ALPHA_D = 76  # 76, 77, 78
DMOL, PC0, EPC0 = 79, 80, 81
# --- reversible fraction of the polymer adsorption (0: irreversible in concentration) ---
REV4 = 82
N_KERNEL_PARAMS = 83
# rows of the per-slug flow array (``slug_flow``)
FLOW_UT, FLOW_T_PV = 0, 1


def _darcy_velocity_and_pv_time(p: dict[str, float], rate_ml_min: float) -> tuple[float, float]:
    """Darcy velocity (m/s) and time per injected pore volume (s) of the core ``p`` at ``rate_ml_min``."""
    area = math.pi * p["DIAMETER"] ** 2 / 4.0
    q = rate_ml_min * units.ML_MIN_TO_M3_S
    return q / area, p["PORO"] * area * p["LENGTH"] / q


def slug_flow(p: dict[str, float], rates_ml_min: np.ndarray) -> np.ndarray:
    """Per-slug flow of the kernel, ``[2, slugs]``: row ``UT`` the Darcy velocity (m/s) and row ``T_PV`` the time per
    pore volume (s) at each slug's rate (``Schedule.rates_ml_min``); a slug at QINJ gets exactly the ``UT`` and
    ``T_PV`` of ``build_kernel_params``."""
    flow = np.empty((2, len(rates_ml_min)))
    for j, rate in enumerate(rates_ml_min):
        flow[FLOW_UT, j], flow[FLOW_T_PV, j] = _darcy_velocity_and_pv_time(p, float(rate))
    return flow


def build_kernel_params(p: dict[str, float], s: dict[str, float]) -> np.ndarray:
    """Pack resolved parameters ``p`` and built-in effect strengths ``s`` into the kernel vector (``UT`` and
    ``T_PV`` at QINJ; the kernel takes each slug's own from ``slug_flow``)."""
    k = np.zeros(N_KERNEL_PARAMS)
    k[PHI] = p["PORO"]
    k[PERM_M2] = p["PERM"] * units.MD_TO_M2
    k[PERM_D] = p["PERM"] * units.MD_TO_DARCY
    k[UT], k[T_PV] = _darcy_velocity_and_pv_time(p, p["QINJ"])
    k[LENGTH] = p["LENGTH"]
    k[SWI], k[C50], k[C60] = p["SWI"], p["C50"], p["C60"]
    k[VIS1], k[VIS2] = p["VIS1"], p["VIS2"]
    k[SIGOW] = 10.0 ** p["XIFTW"]

    k[AP1], k[AP2], k[AP3], k[BETAP], k[CSE1] = p["AP1"], p["AP2"], p["AP3"], p["BETAP"], p["CSE1"]
    k[SSLOPE] = s["polymer_salinity"] * p["SSLOPE"]
    k[GAMMAC], k[GAMHF], k[POWN], k[IGAMHF] = p["GAMMAC"], p["GAMHF"], p["POWN"], p["IGAMHF"]
    k[A0], k[A1], k[A2] = p["A0"], p["A1"], p["A2"]
    k[S_SHEAR] = s["shear_thinning"]
    k[BRK], k[CRK], k[RKCAP] = p["BRK"], p["CRK"], p["RKCAP"]
    k[S_RK] = s["permeability_reduction"]
    ipv = s["inaccessible_pore_volume"]
    k[EPHI3] = 1.0 - ipv * (1.0 - p["EPHI3"])
    k[EPHI4] = 1.0 - ipv * (1.0 - p["EPHI4"])

    k[EPSME], k[CSEL], k[CSEU] = p["EPSME"], p["CSEL"], p["CSEU"]
    k[HB0], k[HB1], k[HB2] = p["HBNC70"], p["HBNC71"], p["HBNC72"]
    k[BETA6], k[F6S], k[CHUH], k[AHUH] = p["BETA6"], p["F6S"], p["CHUH"], p["AHUH"]
    for i in range(5):
        k[AV1 + i] = p[f"ALPHAV{i + 1}"]

    cdc = s["capillary_desaturation"]
    for l in range(3):
        n = l + 1
        k[T1 + l] = cdc * p[f"T{n}{n}"]
        k[SR_LOW + l], k[KR_LOW + l], k[N_LOW + l] = p[f"S{n}RWC"], p[f"P{n}RWC"], p[f"E{n}WC"]
        k[SR_HIGH + l], k[KR_HIGH + l], k[N_HIGH + l] = p[f"S{n}RC"], p[f"P{n}RC"], p[f"E{n}C"]
        k[ALPHA_D + l] = s["dispersion"] * p[f"ALPHAL{n}"] * units.FT_TO_M / p["LENGTH"]
    k[CDC] = 1.0 if cdc > 0.0 else 0.0

    k[AD31] = s["surfactant_adsorption"] * p["AD31"]
    k[AD32] = s["surfactant_adsorption"] * p["AD32"]
    k[B3D] = p["B3D"]
    k[AD41] = s["polymer_adsorption"] * p["AD41"]
    k[AD42] = s["polymer_adsorption"] * p["AD42"]
    k[B4D] = p["B4D"]
    kin = s["kinetic_adsorption"]
    k[KADS] = p["KADS"] / kin if kin > 0.0 else 0.0  # 0 = equilibrium adsorption
    k[REV4] = p["ADSREV4"] + s["reversible_polymer_adsorption"] * (1.0 - p["ADSREV4"])

    k[DMOL] = s["dispersion"] * p["DMOL"]
    k[PC0] = s["capillary_pressure"] * p["CPC0"]
    k[EPC0] = p["EPC0"]
    return k
