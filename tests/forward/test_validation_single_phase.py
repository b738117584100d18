"""Forward model vs single-phase analytic references (Ogata & Banks 1961; Darcy with resistance factors, Lake 1989 ch.
5; test ladder step 4).

The core is fully water saturated (SWI = 1, no residual oil, k_rw° = 1), so Darcy's law and the 1-D
advection-dispersion-adsorption equation hold exactly:

* salinity tracer with longitudinal dispersion (Pe = L/alpha_L = 200): effluent vs Ogata-Banks;
* polymer step with scaled IPV (EPHI4) and Langmuir adsorption, no dispersion: effluent midpoint at
  ``(1 - phi_IPV) + D``;
* the same polymer flood's pressure drop: a linear ramp while the piston front crosses the core, the plateau
  ``RF = mu_p R_k/mu_w`` and, after a water post-flush, ``RRF = R_k`` -- with ``mu_p`` from Flory-Huggins and
  ``R_k`` from thesis Eqs. 2.7-2.8 evaluated here from the inputs, and absolute pressures from Darcy's law in SI.
"""

import math
from functools import lru_cache

import numpy as np
import pytest

from oracles import (
    crossing_time,
    flory_huggins_viscosity,
    interval_midpoints,
    langmuir_retardation,
    ogata_banks,
    permeability_reduction,
    piston_pressure_ratio,
    retarded_midpoint_pv,
)
from spflow.plugins.forward.simulate import simulate

# core and fluid (SI conversions written out here, independent of spflow.units)
LENGTH_M, DIAMETER_M, PORO, PERM_MD, QINJ_ML_MIN, VIS1_CP = 0.1524, 0.0508, 0.23, 700.0, 0.25, 1.0
WATER_FILLED = {
    "SWI": 1.0, "S1RWC": 0.0, "S2RWC": 0.0, "S3RWC": 0.0, "P1RWC": 1.0,
    "LENGTH": LENGTH_M, "DIAMETER": DIAMETER_M, "PORO": PORO, "PERM": PERM_MD, "QINJ": QINJ_ML_MIN, "VIS1": VIS1_CP,
}
INITIAL_PPM, INJECTED_PPM = 9400.0, 17500.0
PECLET = 200.0
FT = 0.3048

POLYMER_PPM = 1000.0
C_WT = POLYMER_PPM / 1.0e4
AP1, AP2, AP3 = 15.0, 0.0, 155.0
BRK, CRK, RKCAP = 100.0, 0.068, 10.0
EPHI4, AD41, B4D = 0.85, 1.0, 100.0
POLYMER_PV, POSTFLUSH_PV = 2.0, 3.0
NO_OTHER_EFFECTS = {"capillary_desaturation": 0.0, "capillary_pressure": 0.0, "shear_thinning": 0.0}


@lru_cache(maxsize=None)
def tracer_run(cells: int):
    params = {**WATER_FILLED, "ALPHAL1": LENGTH_M / PECLET / FT}  # dispersivity in ft
    return simulate(
        [{"pv": 1.6, "salinity_ppm": INJECTED_PPM}], params, cells=cells,
        effects={**NO_OTHER_EFFECTS, "dispersion": 1.0}, scheme="tvd", pv_step=0.005,
    )


@lru_cache(maxsize=None)
def polymer_run(cells: int):
    params = {
        **WATER_FILLED, "AP1": AP1, "AP2": AP2, "AP3": AP3, "BRK": BRK, "CRK": CRK, "RKCAP": RKCAP,
        "EPHI4": EPHI4, "AD41": AD41, "AD42": 0.0, "B4D": B4D,
    }
    schedule = [
        {"pv": POLYMER_PV, "salinity_ppm": INITIAL_PPM, "polymer_ppm": POLYMER_PPM},
        {"pv": POSTFLUSH_PV, "salinity_ppm": INITIAL_PPM},
    ]
    effects = {
        **NO_OTHER_EFFECTS, "dispersion": 0.0, "polymer_salinity": 0.0, "permeability_reduction": 1.0,
        "inaccessible_pore_volume": 1.0, "polymer_adsorption": 1.0,
    }
    return simulate(schedule, params, cells=cells, effects=effects, scheme="tvd", pv_step=0.005)


def water_pressure_drop_pa() -> float:
    """Darcy: dp = q mu L / (k A) in Pa for the water-filled core."""
    q = QINJ_ML_MIN * 1e-6 / 60.0
    area = math.pi * DIAMETER_M**2 / 4.0
    return q * VIS1_CP * 1e-3 * LENGTH_M / (PERM_MD * 9.869233e-16 * area)


def polymer_front_retardation() -> float:
    return retarded_midpoint_pv(1.0 - EPHI4, langmuir_retardation(AD41, B4D, C_WT))


def resistance_factors() -> tuple[float, float]:
    """(RF, RRF) of the polymer: mu_p R_k / mu_w and R_k (thesis Eqs. 2.1, 2.6-2.8, salinity factor 1)."""
    mu_p = flory_huggins_viscosity(C_WT, VIS1_CP, AP1, AP2, AP3)
    r_k = permeability_reduction(C_WT, BRK, CRK, AP1, PERM_MD * 1e-3, PORO, cap=RKCAP)
    return mu_p * r_k / VIS1_CP, r_k


def interval_averages(pv, exact, nodes: int = 16):
    """Averages of ``exact(t)`` over the output intervals ``(pv[k-1], pv[k]]`` (Gauss-Legendre), as the effluent
    series are interval averages."""
    x, w = np.polynomial.legendre.leggauss(nodes)
    lo, hi = pv[:-1, None], pv[1:, None]
    t = 0.5 * (hi - lo) * x + 0.5 * (hi + lo)
    return (exact(t) * w).sum(axis=1) / 2.0


def test_salinity_tracer_matches_ogata_banks():
    times = np.array([0.8, 0.9, 1.0, 1.1, 1.2, 1.3])
    errors = []
    for cells in (50, 400):
        ds = tracer_run(cells)
        pv = ds["pv"].values
        salinity = ds["salinity_out"].values
        assert salinity[0] == pytest.approx(INITIAL_PPM, rel=1e-6)
        at_times = np.interp(times, interval_midpoints(pv), salinity)
        relative = (at_times - INITIAL_PPM) / (INJECTED_PPM - INITIAL_PPM)
        averaged = interval_averages(pv, lambda t: ogata_banks(1.0, t, PECLET))
        exact = np.interp(times, interval_midpoints(pv), np.concatenate([[0.0], averaged]))
        errors.append(float(np.max(np.abs(relative - exact))))
    # numerical dispersion adds to the physical one: the gap must shrink with the grid and be small at 400 cells
    # (from ~200 cells on it sits at a ~1e-3 floor: Ogata-Banks fixes the inlet concentration, the simulator has
    # Danckwerts conditions, and its dispersion is backward Euler in time)
    assert errors[1] < 0.25 * errors[0], f"max |C/C0 - Ogata-Banks| at 50/400 cells: {errors}"
    assert errors[1] < 0.015, f"max |C/C0 - Ogata-Banks| at 400 cells: {errors[1]:.4f}"


def test_polymer_effluent_midpoint_is_retarded_pore_volume():
    ds = polymer_run(400)
    midpoint = crossing_time(interval_midpoints(ds["pv"].values), ds["c_polymer_out"].values, 0.5 * POLYMER_PPM)
    expected = polymer_front_retardation()
    assert midpoint == pytest.approx(expected, rel=0.01), f"midpoint {midpoint:.4f} PV vs (1-IPV)+D = {expected:.4f}"


def test_pressure_drop_ramp_plateau_and_residual_resistance():
    ds = polymer_run(400)
    pv, dp = ds["pv"].values, ds["dp"].values
    dp_w = water_pressure_drop_pa()
    rf, rrf = resistance_factors()
    retard = polymer_front_retardation()
    # ramp and plateau during polymer injection, absolute Pa from Darcy's law in series
    times = np.array([0.1, 0.3, 0.5, 0.7, 0.85, 1.2, 1.9]) * retard
    times = times[times < POLYMER_PV]
    expected = dp_w * piston_pressure_ratio(times, rf, retard)
    np.testing.assert_allclose(np.interp(times, pv, dp), expected, rtol=0.02, err_msg="dp(t) during polymer")
    # the ramp is a straight line of slope dp_w (RF - 1)/R
    ramp = (pv > 0.15 * retard) & (pv < 0.85 * retard)
    slope = np.polyfit(pv[ramp], dp[ramp], 1)[0]
    assert slope == pytest.approx(dp_w * (rf - 1.0) / retard, rel=0.02)
    # after 3 PV of water post-flush: residual resistance factor = R_k (irreversible permeability reduction)
    end = pv >= POLYMER_PV + POSTFLUSH_PV - 0.2
    assert float(np.mean(dp[end])) / dp_w == pytest.approx(rrf, rel=0.01)
