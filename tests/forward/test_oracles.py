"""Self-tests of the analytic oracles in ``tests/oracles`` against closed forms (the sources each oracle names) and
against
conservation laws evaluated by independent numerical quadrature of the oracle profiles."""

import math

import numpy as np
import pytest
from scipy.integrate import quad
from scipy.optimize import minimize_scalar
from scipy.special import erfc

from oracles import (
    CoreyFractionalFlow,
    cell_average,
    buckley_leverett,
    chemical_flood,
    flory_huggins_viscosity,
    langmuir_retardation,
    ogata_banks,
    ogata_banks_time_at,
    permeability_reduction,
    piston_pressure_ratio,
    retarded_midpoint_pv,
    slug_consumption_distance,
    storage_coefficients,
    tertiary_chemical_flood,
    welge_front_saturation,
)

WATER = CoreyFractionalFlow(swc=0.2, sor=0.3, krw0=0.3, kro0=0.8, nw=2.5, no=2.0, mu_w=1.0, mu_o=13.8)
POLYMER = CoreyFractionalFlow(swc=0.2, sor=0.3, krw0=0.3, kro0=0.8, nw=2.5, no=2.0, mu_w=10.0, mu_o=13.8)
BL_CASES = [
    CoreyFractionalFlow(mu_o=0.5),
    CoreyFractionalFlow(mu_o=1.0),
    CoreyFractionalFlow(mu_o=2.0),
    WATER,
]


def profile_integral(fan, t_d, x_max=None, weight=lambda s: s):
    """Quadrature of ``weight(S(x, t_D)) - weight(S_init)`` over ``[0, x_max]`` with the shocks as break points."""
    x_max = 1.0 if x_max is None else x_max
    breaks = [v * t_d for v in fan.shock_speeds() if v * t_d < x_max]
    s0 = weight(fan.s_init)
    value, _ = quad(lambda x: weight(float(fan.profile(x, t_d))) - s0, 0.0, x_max, points=breaks or None, limit=400)
    return value


# ---------------------------------------------------------------- Buckley-Leverett


def test_buckley_leverett_closed_form_example_2_1a():
    flux = CoreyFractionalFlow()  # S_wc = S_or = 0, n = 2, k_r° = 1, mu_o = mu_w
    s_f = welge_front_saturation(flux, 0.0)
    assert s_f == pytest.approx(1.0 / math.sqrt(2.0), abs=1e-12)
    assert float(flux.fw(s_f)) == pytest.approx((2.0 + math.sqrt(2.0)) / 4.0, abs=1e-12)
    fan = buckley_leverett(flux)
    t_bt = 1.0 / fan.shock_speeds()[-1]
    assert t_bt == pytest.approx(2.0 * (math.sqrt(2.0) - 1.0), abs=1e-12)
    assert float(fan.cumulative_oil(t_bt)) == pytest.approx(t_bt, abs=1e-12)
    np.testing.assert_allclose(fan.cumulative_oil([1.0, 2.0]), [0.84986, 0.91002], atol=1e-5)
    np.testing.assert_allclose(fan.outlet_saturation([1.0, 2.0]), [0.74293, 0.84063], atol=1e-5)


@pytest.mark.parametrize("flux", BL_CASES)
def test_buckley_leverett_front_is_welge_tangent(flux):
    s_f = welge_front_saturation(flux, flux.swc)
    chord = float(flux.fw(s_f)) / (s_f - flux.swc)
    assert float(flux.dfw(s_f)) == pytest.approx(chord, rel=1e-10)
    # the tangent point maximises the chord slope (independent bounded optimisation)
    best = minimize_scalar(
        lambda s: -float(flux.fw(s)) / (s - flux.swc), bounds=(flux.swc + 1e-6, flux.s_max), method="bounded",
        options={"xatol": 1e-10},
    )
    assert s_f == pytest.approx(best.x, abs=1e-6)


@pytest.mark.parametrize("flux", BL_CASES)
@pytest.mark.parametrize("s_init_offset", [0.0, 0.05])
def test_buckley_leverett_profile_conserves_water_before_breakthrough(flux, s_init_offset):
    s_init = flux.swc + s_init_offset
    fan = buckley_leverett(flux, s_init)
    t_d = 0.9 / fan.shock_speeds()[-1]
    expected = t_d * (1.0 - float(flux.fw(s_init)))  # water injected minus water produced at f(S_init)
    assert profile_integral(fan, t_d) == pytest.approx(expected, rel=1e-7)
    assert float(fan.cumulative_oil(t_d)) == pytest.approx(expected, rel=1e-10)


@pytest.mark.parametrize("flux", BL_CASES)
def test_exact_cell_averages_match_fine_sampling(flux):
    fan = buckley_leverett(flux)
    t_d = 0.7 / fan.shock_speeds()[-1]
    sampled = cell_average(lambda x: fan.profile(x, t_d), 10, samples_per_cell=250)
    np.testing.assert_allclose(fan.cell_averages(t_d, 10), sampled, atol=4e-3)  # sampling error <= jump/250


@pytest.mark.parametrize("flux", BL_CASES)
def test_buckley_leverett_welge_production_after_breakthrough(flux):
    fan = buckley_leverett(flux)
    t_bt = 1.0 / fan.shock_speeds()[-1]
    for t_d in (1.3 * t_bt, 3.0):
        s_out = float(fan.outlet_saturation(t_d))
        assert float(flux.dfw(s_out)) == pytest.approx(1.0 / t_d, rel=1e-9)
        welge = s_out + t_d * (1.0 - float(flux.fw(s_out))) - flux.swc
        # independent: time integral of the outlet oil cut
        produced, _ = quad(lambda t: float(fan.oil_cut(t)), 1e-9, t_d, points=[t_bt], limit=400)
        assert float(fan.cumulative_oil(t_d)) == pytest.approx(welge, rel=1e-10)
        assert produced == pytest.approx(welge, rel=1e-6)
        assert profile_integral(fan, t_d) == pytest.approx(welge, rel=1e-7)


def test_corey_rejects_bad_input():
    with pytest.raises(ValueError, match="swc"):
        CoreyFractionalFlow(swc=1.2)
    with pytest.raises(ValueError, match="nw"):
        CoreyFractionalFlow(nw=0.5)
    with pytest.raises(ValueError, match="mu_o"):
        CoreyFractionalFlow(mu_o=0.0)


# ---------------------------------------------------------------- polymer Riemann problem


def test_polymer_without_viscosity_ipv_or_adsorption_is_buckley_leverett():
    bl = buckley_leverett(WATER)
    tracer = chemical_flood(WATER, WATER)
    x = np.linspace(0.0, 1.0, 201)
    for t_d in (0.2, 0.35, 0.8):
        np.testing.assert_allclose(tracer.profile(x, t_d), bl.profile(x, t_d), atol=1e-9)
    np.testing.assert_allclose(tracer.cumulative_oil([0.3, 1.0, 3.0]), bl.cumulative_oil([0.3, 1.0, 3.0]), atol=1e-9)
    assert tracer.bank_breakthrough_pv == pytest.approx(1.0 / bl.shock_speeds()[-1], rel=1e-9)
    # with S_wc = 0 the tracer front is the water front itself (tangents from the same point)
    clean = CoreyFractionalFlow(mu_o=2.0)
    assert chemical_flood(clean, clean).speed_chemical == pytest.approx(buckley_leverett(clean).shock_speeds()[-1])


@pytest.mark.parametrize("ipv, retardation", [(0.0, 0.0), (0.15, 0.0), (0.0, 0.2), (0.2, 0.05)])
def test_offset_ipv_front_is_tangent_from_pivot(ipv, retardation):
    flood = chemical_flood(WATER, POLYMER, retardation=retardation, ipv=ipv, ipv_form="offset")
    pivot = ipv - retardation
    best = minimize_scalar(
        lambda s: -float(POLYMER.fw(s)) / (s - pivot), bounds=(max(pivot, POLYMER.swc) + 1e-6, POLYMER.s_max),
        method="bounded", options={"xatol": 1e-10},
    )
    assert flood.s_1 == pytest.approx(best.x, abs=1e-6)
    assert flood.speed_chemical == pytest.approx(-best.fun, rel=1e-9)


@pytest.mark.parametrize("form", ["offset", "scaled"])
@pytest.mark.parametrize("ipv, retardation", [(0.0, 0.0), (0.15, 0.0), (0.0, 0.1), (0.15, 0.1)])
def test_polymer_wave_structure_balances_volumes(form, ipv, retardation):
    flood = chemical_flood(WATER, POLYMER, retardation=retardation, ipv=ipv, ipv_form=form)
    a, b = storage_coefficients(ipv, retardation, form)
    # Rankine-Hugoniot across the chemical front and the bank admissibility
    lam_c = flood.speed_chemical
    assert float(POLYMER.dfw(flood.s_1)) == pytest.approx(lam_c, rel=1e-9)
    assert lam_c * (flood.s_1 - flood.s_bank) == pytest.approx(
        float(POLYMER.fw(flood.s_1)) - float(WATER.fw(flood.s_bank)), abs=1e-10)
    lam_b = float(WATER.fw(flood.s_bank)) / (flood.s_bank - WATER.swc)
    assert flood.s_bank < welge_front_saturation(WATER, WATER.swc)  # direct-shock case for this viscosity ratio
    assert float(WATER.dfw(flood.s_bank)) >= lam_b >= float(WATER.dfw(WATER.swc))
    assert 1.0 / flood.bank_breakthrough_pv == pytest.approx(lam_b, rel=1e-9)
    # water: everything injected is stored before breakthrough (quadrature of the profile)
    t_d = 0.8 * flood.bank_breakthrough_pv
    assert profile_integral(flood.fan, t_d) == pytest.approx(t_d, rel=1e-7)
    # chemical: (a S + b) c integrated behind the front vs injected; defect (1 - a)(1 - f_c(S_1)) is the scaled form's
    stored = profile_integral(flood.fan, t_d, x_max=lam_c * t_d, weight=lambda s: a * s + b)
    stored += (a * WATER.swc + b) * lam_c * t_d
    expected_defect = (1.0 - a) * (1.0 - float(POLYMER.fw(flood.s_1)))
    assert (t_d - stored) / t_d == pytest.approx(expected_defect, abs=1e-7)
    assert flood.chemical_balance_defect() == pytest.approx(expected_defect, abs=1e-10)


def test_polymer_production_matches_piecewise_formula():
    flood = chemical_flood(WATER, POLYMER, retardation=0.1, ipv=0.15, ipv_form="offset")
    t_b, t_c = flood.bank_breakthrough_pv, flood.chemical_breakthrough_pv
    f_b = float(WATER.fw(flood.s_bank))

    def piecewise(t):  # Pope 1980, direct-shock case, f_wi = 0
        if t <= t_b:
            return t
        if t <= t_c:
            return t_b + (t - t_b) * (1.0 - f_b)
        s_out = float(flood.outlet_saturation(t))
        return s_out + t * (1.0 - float(POLYMER.fw(s_out))) - WATER.swc

    times = [0.5 * t_b, t_b, 0.5 * (t_b + t_c), t_c * 1.0001, 1.5, 4.0]
    np.testing.assert_allclose(flood.cumulative_oil(times), [piecewise(t) for t in times], rtol=1e-9)
    assert float(flood.oil_cut(0.5 * (t_b + t_c))) == pytest.approx(1.0 - f_b, rel=1e-12)


def test_weak_polymer_bank_leads_with_a_buckley_leverett_shock():
    thin = CoreyFractionalFlow(swc=0.2, sor=0.3, krw0=0.3, kro0=0.8, nw=2.5, no=2.0, mu_w=1.3, mu_o=13.8)
    flood = chemical_flood(WATER, thin)
    s_f = welge_front_saturation(WATER, WATER.swc)
    assert flood.s_bank > s_f
    assert flood.fan.shock_speeds()[-1] == pytest.approx(float(WATER.dfw(s_f)), rel=1e-10)
    t_d = 0.9 * flood.bank_breakthrough_pv
    assert profile_integral(flood.fan, t_d) == pytest.approx(t_d, rel=1e-7)


def test_storage_coefficients_reject_bad_input():
    with pytest.raises(ValueError, match="ipv_form"):
        storage_coefficients(0.1, 0.0, "shifted")
    with pytest.raises(ValueError, match="ipv"):
        storage_coefficients(1.0, 0.0, "scaled")
    with pytest.raises(ValueError, match="retardation"):
        storage_coefficients(0.1, -0.1, "offset")


# ---------------------------------------------------------------- tertiary SP


def test_tertiary_flood_bank_and_breakthrough():
    high_nc = CoreyFractionalFlow(swc=0.0, sor=0.0, krw0=1.0, kro0=1.0, nw=2.0, no=2.0, mu_w=10.0, mu_o=13.8)
    flood = tertiary_chemical_flood(WATER, high_nc, retardation=0.1)
    s_wi = WATER.s_max
    assert flood.s_bank < s_wi
    lam_b = (1.0 - float(WATER.fw(flood.s_bank))) / (s_wi - flood.s_bank)
    assert 1.0 / flood.bank_breakthrough_pv == pytest.approx(lam_b, rel=1e-9)
    assert flood.bank_breakthrough_pv < flood.chemical_breakthrough_pv
    assert float(flood.cumulative_oil(0.95 * flood.bank_breakthrough_pv)) == pytest.approx(0.0, abs=1e-12)
    t_d = 0.5 * (flood.bank_breakthrough_pv + flood.chemical_breakthrough_pv)
    expected = (t_d - flood.bank_breakthrough_pv) * (1.0 - float(WATER.fw(flood.s_bank)))
    assert float(flood.cumulative_oil(t_d)) == pytest.approx(expected, rel=1e-9)
    # all the mobilised oil is counted: water balance of the profile before bank breakthrough is zero net inflow
    t_early = 0.8 * flood.bank_breakthrough_pv
    assert profile_integral(flood.fan, t_early) == pytest.approx(0.0, abs=1e-8)
    # eventually the high-Nc curve recovers (nearly) all residual oil: S_out -> 1 - S_orc
    assert float(flood.cumulative_oil(200.0)) == pytest.approx(WATER.sor - high_nc.sor, abs=5e-3)


def test_tertiary_flood_without_bank_is_rejected():
    with pytest.raises(ValueError, match="bank"):
        tertiary_chemical_flood(WATER, WATER)


def test_slug_consumption_distance():
    d_s = langmuir_retardation(1.0 + 0.5 * 0.3, 1000.0, 0.01)  # surfactant Langmuir row of docs/forward_model.md
    assert d_s == pytest.approx(0.1045, abs=5e-5)
    assert slug_consumption_distance(0.3, d_s) == pytest.approx(0.3 / 0.104545, rel=1e-4)
    assert slug_consumption_distance(0.3, 0.5) == pytest.approx(0.6)
    with pytest.raises(ValueError, match="retardation"):
        slug_consumption_distance(0.3, 0.0)


# ---------------------------------------------------------------- Ogata-Banks


@pytest.mark.parametrize(
    "retardation, expected",
    [(1.0, [0.1573, 0.5199, 0.8424, 0.9698]), (1.0636, [0.0521, 0.2852, 0.6506, 0.8959])],
)
def test_ogata_banks_table(retardation, expected):
    values = ogata_banks(1.0, np.array([0.9, 1.0, 1.1, 1.2]), 200.0, retardation)
    np.testing.assert_allclose(values, expected, atol=5e-5)


def test_ogata_banks_matches_direct_formula_where_it_does_not_overflow():
    x, t, pe, r = 0.3, np.array([0.2, 0.3, 0.4]), 20.0, 1.2
    w = 2.0 * np.sqrt(t / (r * pe))
    direct = 0.5 * (erfc((x - t / r) / w) + np.exp(pe * x) * erfc((x + t / r) / w))
    np.testing.assert_allclose(ogata_banks(x, t, pe, r), direct, rtol=1e-12)


def test_effluent_midpoint_tends_to_retarded_pore_volume():
    polymer_langmuir_d = langmuir_retardation(0.7, 100.0, 0.1)
    assert polymer_langmuir_d == pytest.approx(0.0636, abs=5e-5)
    midpoint = retarded_midpoint_pv(0.15, polymer_langmuir_d)
    errors = [abs(ogata_banks_time_at(0.5, pe, midpoint) - midpoint) / midpoint for pe in (50.0, 200.0, 1000.0)]
    assert errors[0] > errors[1] > errors[2]
    assert all(err < 1.0 / pe for err, pe in zip(errors, (50.0, 200.0, 1000.0)))


# ---------------------------------------------------------------- single-phase polymer pressure


def test_flory_huggins_property_value():
    # docs/forward_model.md, Property values: C_p = 0.1 wt %, C_SEP = 0.2 meq/ml, AP1..3 = 20, 300, 2000, SSLOPE =
    # -0.3, mu_w = 0.8 cP
    assert flory_huggins_viscosity(0.1, 0.8, 20.0, 300.0, 2000.0, 0.2**-0.3) == pytest.approx(9.8757, abs=5e-5)


def test_permeability_reduction_limits():
    kwargs = dict(brk=100.0, crk=0.068, ap1=15.0, perm_darcy=0.7, porosity=0.23)
    assert permeability_reduction(0.0, **kwargs) == 1.0
    rk_max = (1.0 - 0.068 * 15.0 ** (1.0 / 3.0) / math.sqrt(0.7 / 0.23)) ** -4
    assert permeability_reduction(1.0e6, **kwargs) == pytest.approx(rk_max, rel=1e-6)
    assert rk_max > 1.2
    assert permeability_reduction(1.0e6, **kwargs, cap=1.2) == pytest.approx(1.2, rel=1e-6)
    half = permeability_reduction(0.01, **kwargs)  # b_rk C = 1: half-way to R_k,max
    assert half == pytest.approx(1.0 + 0.5 * (rk_max - 1.0), rel=1e-12)


def test_piston_pressure_ratio_is_series_darcy_resistance():
    # SI check: q/(kA) [mu_p R_k x_f + mu_w (L - x_f)] over q mu_w L/(kA)
    q, k, area, length, phi = 1e-8, 5e-13, 2e-3, 0.15, 0.23
    mu_w, mu_p, r_k, retard = 1e-3, 8e-3, 2.0, 0.9
    u = q / area
    for t_seconds in (0.0, 600.0, 3000.0, 1e5):
        x_f = min(u * t_seconds / (phi * retard), length)
        dp = q / (k * area) * (mu_p * r_k * x_f + mu_w * (length - x_f))
        t_d = u * t_seconds / (phi * length)
        assert float(piston_pressure_ratio(t_d, mu_p * r_k / mu_w, retard)) == pytest.approx(
            dp / (q * mu_w * length / (k * area)), rel=1e-12)


# ---------------------------------------------------------------- comparison helpers


def test_comparison_helpers_on_known_data():
    from oracles import crossing_time, interval_midpoints, l1_error, observed_order

    step = cell_average(lambda x: np.where(x < 0.3, 1.0, 0.0), 4, samples_per_cell=1000)
    np.testing.assert_allclose(step, [1.0, 0.2, 0.0, 0.0], atol=1e-12)
    assert l1_error(np.zeros(4), step) == pytest.approx(0.3, abs=1e-12)
    t = np.linspace(0.0, 2.0, 21)
    assert crossing_time(t, 3.0 * t, 1.5) == pytest.approx(0.5, abs=1e-12)
    assert crossing_time(t, 1.0 - t, 0.25) == pytest.approx(0.75, abs=1e-12)
    assert observed_order([50, 100, 200], [0.04, 0.02, 0.01]) == pytest.approx(1.0, abs=1e-12)
    np.testing.assert_allclose(interval_midpoints([0.0, 0.1, 0.2, 0.25]), [0.0, 0.05, 0.15, 0.225], atol=1e-15)
    with pytest.raises(ValueError, match="never reaches"):
        crossing_time(t, t, 5.0)
