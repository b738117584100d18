"""NPV economics (thesis Eqs. 4.7-4.11, Table 4.2) against hand-built cash flows discounted term by term."""

import numpy as np
import pytest
import xarray as xr

from spflow.core.errors import ParameterError
from spflow.plugins.forward.schedule import Schedule, Slug
from spflow.plugins.slug_design.economics import (Economics, ScaleUp, annual_chemical_cost, annual_oil_bbl, npv,
                                                  project_npv)

# Exact definitions (NIST): 1 bbl = 42 US gal = 0.158987294928 m^3, 1 lb = 0.45359237 kg.
BBL_M3, LB_KG = 0.158987294928, 0.45359237


def discounted(flows, d, capital):
    """Eq. 4.7 written out: cash of year j discounted by (1 + d)^j, minus the capital."""
    total = -capital
    for j, c in enumerate(flows, start=1):
        total += c / (1.0 + d) ** j
    return total


def test_npv_equals_term_by_term_discounting():
    flows = [120.0, -40.0, 300.0, 55.5]
    assert npv(np.array(flows), 0.2, 100.0) == pytest.approx(discounted(flows, 0.2, 100.0), rel=1e-14)
    # several price paths at once: one NPV per row
    rows = np.array([flows, [0.0, 0.0, 0.0, 1.2e6]])
    assert npv(rows, 0.07, 5.0) == pytest.approx([discounted(r, 0.07, 5.0) for r in rows], rel=1e-14)
    # a perpetuity-like check: constant C over N years = C (1 - (1+d)^-N) / d
    assert npv(np.full(13, 1000.0), 0.2, 0.0) == pytest.approx(1000.0 * (1 - 1.2 ** -13) / 0.2, rel=1e-13)


def hand_built_case():
    """A 3-year project with chemical slugs straddling the year boundaries and a piecewise-constant oil cut."""
    economics = Economics(capital_usd=50_000.0, salt_usd_per_lb=0.5, surfactant_usd_per_lb=5.0,
                          polymer_usd_per_lb=2.0, tde_usd_per_year=10_000.0, discount_rate=0.2, years=3)
    scale = ScaleUp(pore_volume_bbl=2.0e4, injection_rate_pv_per_year=0.5, start_pv=1.0)
    schedule = Schedule((Slug("IWF", 1.0, 9400.0), Slug("HTDS", 0.3, 17500.0),
                         Slug("SP", 0.4, 17500.0, 6000.0, 3000.0), Slug("P", 0.5, 9400.0, 0.0, 2000.0),
                         Slug("EWF", 0.3, 9400.0)))
    # oil cut (interval averages on a 0.05 PV grid): 0.3 before 1.0 PV (IWF, not in the project), 0.2 on (1.0, 1.6],
    # 0.4 on (1.6, 2.1], 0 after
    pv = np.round(np.arange(0, 2.5 + 1e-9, 0.05), 10)
    cut = np.where(pv <= 1.0 + 1e-9, 0.3, np.where(pv <= 1.6 + 1e-9, 0.2, np.where(pv <= 2.1 + 1e-9, 0.4, 0.0)))
    response = xr.Dataset({"oil_cut": ("pv", cut)}, coords={"pv": pv})
    return economics, scale, schedule, response


def test_project_npv_of_a_hand_built_example():
    economics, scale, schedule, response = hand_built_case()
    # years in PV: [1.0, 1.5], [1.5, 2.0], [2.0, 2.5]
    oil_pv = [0.5 * 0.2, 0.1 * 0.2 + 0.4 * 0.4, 0.1 * 0.4]
    oil_bbl = np.array(oil_pv) * 2.0e4
    lb_per_pv = 1000.0 * 2.0e4 * BBL_M3 / LB_KG
    # $ per PV of each chemical slug: ppm * 1e-6 * lb/PV * $/lb
    htds = 17500e-6 * 0.5 * lb_per_pv
    sp = (17500e-6 * 0.5 + 6000e-6 * 5.0 + 3000e-6 * 2.0) * lb_per_pv
    p = (9400e-6 * 0.5 + 2000e-6 * 2.0) * lb_per_pv
    # slugs in PV: HTDS [1.0, 1.3], SP [1.3, 1.7], P [1.7, 2.2]
    chem = np.array([0.3 * htds + 0.2 * sp, 0.2 * sp + 0.3 * p, 0.2 * p])
    prices = np.array([[70.0, 80.0, 90.0], [60.0, 60.0, 61.0]])
    expected = [discounted(s * oil_bbl - chem - 10_000.0, 0.2, 50_000.0) for s in prices]
    assert project_npv(response, schedule, prices, scale, economics) == pytest.approx(expected, rel=1e-10)
    assert annual_oil_bbl(response["pv"].values, response["oil_cut"].values, scale, 3) == pytest.approx(oil_bbl,
                                                                                                       rel=1e-10)
    assert annual_chemical_cost(schedule, scale, economics) == pytest.approx(chem, rel=1e-12)


def test_annual_oil_conserves_the_tertiary_oil_and_stops_at_the_end_of_the_flood():
    rng = np.random.default_rng(3)
    pv = np.cumsum(np.r_[0.0, rng.uniform(0.005, 0.03, 300)])  # uneven grid to ~4.5 PV
    cut = rng.uniform(0.0, 0.6, pv.size)
    scale = ScaleUp(pore_volume_bbl=7.0e4, injection_rate_pv_per_year=0.25, start_pv=1.0)
    years = int(np.ceil((pv[-1] - 1.0) / 0.25)) + 3  # three years past the end of the flood
    oil = annual_oil_bbl(pv, cut, scale, years)
    produced = sum(c * dp for c, dp, right in zip(cut[1:], np.diff(pv), pv[1:]) if right > 1.0)
    partial = next(i for i in range(pv.size) if pv[i] > 1.0)  # interval straddling the project start
    produced -= cut[partial] * (1.0 - pv[partial - 1])
    assert oil.sum() == pytest.approx(produced * 7.0e4, rel=1e-10)
    assert np.all(oil[-3:] == 0.0) and np.all(oil >= 0.0)


def test_table_4_2_defaults_and_unit_conversion():
    e, s = Economics(), ScaleUp()
    assert (e.capital_usd, e.salt_usd_per_lb, e.surfactant_usd_per_lb, e.polymer_usd_per_lb, e.tde_usd_per_year,
            e.discount_rate, e.years) == (2.0e5, 0.5, 5.0, 2.0, 1.0e4, 0.2, 13)
    assert s.brine_lb_per_pv == pytest.approx(1.0e5 * BBL_M3 * 1000.0 / LB_KG, rel=1e-12)  # ~350.5 lb/bbl
    assert s.end_pv(13) == pytest.approx(4.5, rel=1e-12)


@pytest.mark.parametrize("make, field", [
    (lambda: Economics(discount_rate=-1.0), "discount_rate"),
    (lambda: Economics(years=2.5), "years"),
    (lambda: Economics(polymer_usd_per_lb=-2.0), "polymer_usd_per_lb"),
    (lambda: Economics(capital_usd=float("nan")), "capital_usd"),
    (lambda: ScaleUp(pore_volume_bbl=0.0), "pore_volume_bbl"),
    (lambda: ScaleUp(injection_rate_pv_per_year=-0.1), "injection_rate_pv_per_year"),
    (lambda: ScaleUp(start_pv=-1.0), "start_pv"),
    (lambda: ScaleUp(brine_density_kg_m3=50.0), "brine_density_kg_m3"),
])
def test_bad_fields_are_named_with_their_range(make, field):
    with pytest.raises(ParameterError, match=rf"{field}.*(range|allowed|whole number)"):
        make()


def test_prices_must_cover_every_project_year():
    economics, scale, schedule, response = hand_built_case()
    with pytest.raises(ParameterError, match="one price per project year"):
        project_npv(response, schedule, np.array([70.0, 80.0]), scale, economics)
