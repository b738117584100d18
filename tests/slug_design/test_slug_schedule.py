"""Slug-size schedules (Table 4.2, Eq. 4.10): constant chemical mass, fixed total PV, named bad inputs."""

import numpy as np
import pytest

from spflow.core.errors import ParameterError
from spflow.plugins.slug_design.economics import Economics, ScaleUp, annual_chemical_cost
from spflow.plugins.slug_design.slug_schedule import design_bounds, slug_schedule


def test_chemical_mass_and_total_pv_are_constant_over_random_designs():
    rng = np.random.default_rng(0)
    for s_htds, s_sp, s_p in rng.uniform(0.1, 1.0, (200, 3)):
        sched = slug_schedule(s_htds, s_sp, s_p, total_pv=4.5)
        assert [s.name for s in sched.slugs] == ["IWF", "HTDS", "SP", "P", "EWF"]
        assert [s.pv for s in sched.slugs[:4]] == pytest.approx([1.0, s_htds, s_sp, s_p], rel=1e-15)
        assert sched.total_pv == pytest.approx(4.5, rel=1e-14)
        surf = sum(s.surfactant_ppm * s.pv for s in sched.slugs)
        poly = {s.name: s.polymer_ppm * s.pv for s in sched.slugs}
        assert surf == pytest.approx(6780.0 * 0.25, rel=1e-13)  # c_ref s_ref of Table 2.5 / 4.2
        assert poly["SP"] == pytest.approx(2500.0 * 0.25, rel=1e-13)  # 2 500 ppm, not Table 4.2's 25 000
        assert poly["P"] == pytest.approx(2500.0 * 0.25, rel=1e-13)
        salts = [s.salinity_ppm for s in sched.slugs]
        assert salts == [9400.0, 17500.0, 17500.0, 9400.0, 9400.0]  # salt concentration constant (Table 4.2)


def test_surfactant_and_polymer_cost_is_the_same_for_every_design():
    """Eq. 4.10 keeps the chemical cost constant: with salt free, the total chemical bill never changes."""
    economics = Economics(salt_usd_per_lb=0.0)
    scale = ScaleUp()
    lb_per_pv = scale.brine_lb_per_pv
    expected = (6780e-6 * 0.25 * 5.0 + 2 * 2500e-6 * 0.25 * 2.0) * lb_per_pv
    rng = np.random.default_rng(1)
    for x in rng.uniform(0.1, 1.0, (20, 3)):
        cost = annual_chemical_cost(slug_schedule(*x, total_pv=4.5), scale, economics)
        assert cost.sum() == pytest.approx(expected, rel=1e-12)
    # the salt bill, by contrast, grows with the slugs: 0.5 $/lb x ppm x slug
    salty = annual_chemical_cost(slug_schedule(1.0, 1.0, 1.0, total_pv=4.5), scale, Economics())
    small = annual_chemical_cost(slug_schedule(0.1, 0.1, 0.1, total_pv=4.5), scale, Economics())
    assert salty.sum() - small.sum() == pytest.approx(0.9 * (17500 + 17500 + 9400) * 1e-6 * 0.5 * lb_per_pv,
                                                      rel=1e-12)


def test_bounds():
    np.testing.assert_array_equal(design_bounds(), [[0.1, 1.0]] * 3)


@pytest.mark.parametrize("args, field", [
    ((0.05, 0.25, 0.25), "s_htds"), ((0.5, 1.2, 0.25), "s_sp"), ((0.5, 0.25, float("nan")), "s_p"),
    ((0.5, 0.25, "big"), "s_p"),
])
def test_bad_slug_sizes_are_named_with_range(args, field):
    with pytest.raises(ParameterError, match=rf"'{field}'.*\[0.1, 1\]"):
        slug_schedule(*args, total_pv=4.5)


def test_total_pv_must_leave_an_extended_water_flood():
    with pytest.raises(ParameterError, match=r"total_pv.*\(4, 1000\]"):
        slug_schedule(1.0, 1.0, 1.0, total_pv=4.0)
