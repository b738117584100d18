"""Forward model vs the continuous-polymer Riemann solution (Pope 1980; Lake ch. 5; ladder step 3).

Secondary polymer floods of a core at connate water: (A) no IPV and no adsorption, (B) Langmuir adsorption,
(C) scaled inaccessible pore volume (EPHI4 = 0.85, UTCHEM's form) for a polymer that does not viscosify
(AP1 = AP2 = AP3 = 0). Polymer viscosity in A/B is Newtonian Flory-Huggins with the salinity exponent switched off,
so the chemical fractional flow uses ``mu_p = mu_w (1 + AP1 c + AP2 c^2 + AP3 c^3)`` (computed here from the inputs,
not read from the simulator). Compared: oil-bank plateau saturation, bank and polymer breakthrough PV and N_p(t). The
tolerances are backed by a refinement check: the L1 errors of the saturation (and, where the exact concentration is
a step, the concentration) profiles fall from 100 to 200 to 400 cells; point quantities are judged at 400 cells.

Why case C has no viscosity: in the scaled-IPV model the polymer concentration is not uniform behind the front (it
enriches towards it, see :mod:`oracles.polymer_riemann`), so the uniform-concentration construction is exact only
when the aqueous viscosity does not depend on concentration. With a viscous polymer (2000 ppm here, EPHI4 = 0.85)
an independent fine-grid solution of the same equations puts polymer breakthrough ~2 % later than that construction.
"""

from dataclasses import replace
from functools import lru_cache

import numpy as np
import pytest

from oracles import (
    CoreyFractionalFlow,
    cell_average,
    chemical_flood,
    corey_params,
    crossing_time,
    flory_huggins_viscosity,
    interval_midpoints,
    l1_error,
    langmuir_retardation,
)
from spflow.plugins.forward.simulate import simulate

WATER = CoreyFractionalFlow(swc=0.2, sor=0.3, krw0=0.3, kro0=0.8, nw=2.5, no=2.0, mu_w=1.0, mu_o=13.8)
POLYMER_PPM = 2000.0
C_WT = POLYMER_PPM / 1.0e4  # 1 wt % = 10 000 ppm
AP1, AP2, AP3 = 15.0, 0.0, 155.0
MU_P = flory_huggins_viscosity(C_WT, WATER.mu_w, AP1, AP2, AP3)  # cP, Newtonian, salinity factor 1
CHEMICAL = replace(WATER, mu_w=MU_P)
NON_VISCOUS = {"AP1": 0.0, "AP2": 0.0, "AP3": 0.0}
BRINE_PPM = 9400.0
NEWTONIAN_POLYMER_ONLY = {
    "capillary_desaturation": 0.0,
    "dispersion": 0.0,
    "capillary_pressure": 0.0,
    "shear_thinning": 0.0,
    "permeability_reduction": 0.0,
    "polymer_salinity": 0.0,
}
AD41, B4D = 3.0, 100.0
# case: (effect overrides, parameter overrides, retardation D, IPV fraction, chemical fractional-flow curve)
CASES = {
    "plain": (dict(inaccessible_pore_volume=0.0, polymer_adsorption=0.0), {}, 0.0, 0.0, CHEMICAL),
    "adsorption": (
        dict(inaccessible_pore_volume=0.0), {"AD41": AD41, "AD42": 0.0, "B4D": B4D},
        langmuir_retardation(AD41, B4D, C_WT), 0.0, CHEMICAL,
    ),
    "scaled_ipv": (dict(polymer_adsorption=0.0), {"EPHI4": 0.85, **NON_VISCOUS}, 0.0, 0.15, WATER),
}
VISCOUS = [case for case in CASES if CASES[case][4] is CHEMICAL]


def oracle(case: str):
    _, _, retardation, ipv, chemical = CASES[case]
    return chemical_flood(WATER, chemical, retardation=retardation, ipv=ipv, ipv_form="scaled")


@lru_cache(maxsize=None)
def run(case: str, cells: int):
    effects, extra, _, _, _ = CASES[case]
    flood = oracle(case)
    t_profile = 0.85 * flood.bank_breakthrough_pv  # leading front at 85 % of the core
    params = {**corey_params(WATER), "AP1": AP1, "AP2": AP2, "AP3": AP3, **extra}
    return simulate(
        [{"pv": 1.6 * flood.chemical_breakthrough_pv, "salinity_ppm": BRINE_PPM, "polymer_ppm": POLYMER_PPM}],
        params,
        cells=cells,
        effects={**NEWTONIAN_POLYMER_ONLY, **effects},
        scheme="tvd",
        pv_step=0.002,
        profiles_at=[t_profile],
    )


def profile_errors(case: str, cells: int) -> tuple[float, float]:
    ds, flood = run(case, cells), oracle(case)
    t_d = float(ds["profile_pv"][0])
    sw = l1_error(ds["sw"].isel(profile_pv=0).values, flood.fan.cell_averages(t_d, cells))
    c_rel = ds["c_polymer"].isel(profile_pv=0).values / POLYMER_PPM
    c = l1_error(c_rel, cell_average(lambda x: flood.concentration(x, t_d), cells, samples_per_cell=200))
    return sw, c


@pytest.mark.parametrize("case", list(CASES))
def test_profile_errors_fall_under_refinement(case):
    errors = [profile_errors(case, n) for n in (100, 200, 400)]
    sw, c = zip(*errors)
    assert sw[0] > sw[1] > sw[2], f"{case}: saturation L1 errors {sw}"
    assert sw[2] < 0.01, f"{case}: 400-cell saturation L1 error {sw[2]:.4f}"
    if CASES[case][3] == 0.0:  # without IPV the exact concentration is a step c_J -> 0
        assert c[0] > c[1] > c[2], f"{case}: polymer L1 errors {c}"
        assert c[2] < 0.02, f"{case}: 400-cell c/c_J L1 error {c[2]:.4f}"


@pytest.mark.parametrize("case", VISCOUS)
def test_oil_bank_plateau_saturation(case):
    ds, flood = run(case, 400), oracle(case)
    t_d = float(ds["profile_pv"][0])
    x = ds["x"].values
    x_chem, x_bank = flood.speed_chemical * t_d, flood.fan.shock_speeds()[-1] * t_d
    inside = (x > x_chem + 0.05) & (x < x_bank - 0.05)
    assert inside.sum() > 20, f"{case}: bank too narrow to measure ({x_chem:.3f}..{x_bank:.3f})"
    plateau = float(np.median(ds["sw"].isel(profile_pv=0).values[inside]))
    assert plateau == pytest.approx(flood.s_bank, abs=0.005), f"{case}: plateau {plateau:.4f} vs S_B {flood.s_bank:.4f}"


@pytest.mark.parametrize("case", list(CASES))
def test_bank_and_polymer_breakthrough(case):
    ds, flood = run(case, 400), oracle(case)
    t_avg = interval_midpoints(ds["pv"].values)  # oil cut and effluent are interval averages
    f_bank = float(WATER.fw(flood.s_bank))
    t_bank = crossing_time(t_avg, 1.0 - ds["oil_cut"].values, 0.5 * f_bank)
    t_poly = crossing_time(t_avg, ds["c_polymer_out"].values, 0.5 * POLYMER_PPM)
    assert t_bank == pytest.approx(flood.bank_breakthrough_pv, rel=0.015), f"{case}: bank BT {t_bank:.4f}"
    assert t_poly == pytest.approx(flood.chemical_breakthrough_pv, rel=0.015), f"{case}: polymer BT {t_poly:.4f}"


@pytest.mark.parametrize("case", list(CASES))
def test_cumulative_oil(case):
    ds, flood = run(case, 400), oracle(case)
    t_b, t_c = flood.bank_breakthrough_pv, flood.chemical_breakthrough_pv
    times = np.array([0.5 * t_b, 0.5 * (t_b + t_c), 1.2 * t_c, 1.5 * t_c])
    n_p_sim = np.interp(times, ds["pv"].values, ds["recovery"].values) * (1.0 - WATER.swc)
    np.testing.assert_allclose(n_p_sim, flood.cumulative_oil(times), rtol=0.01, err_msg=f"{case}: N_p(t)")
