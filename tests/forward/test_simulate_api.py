"""The public ``simulate()`` contract: Dataset layout, units, attrs, profiles, determinism, physical direction."""

import math

import numpy as np
import pytest

from spflow.plugins.forward.effects import BUILTIN_EFFECTS
from spflow.plugins.forward.parameters import PARAMETERS
from spflow.plugins.forward.schedule import BCF_SCHEDULES, Schedule, Slug
from spflow.plugins.forward.simulate import simulate

SERIES = {"dp": "Pa", "oil_cut": "1", "recovery": "1", "c_polymer_out": "ppm", "c_surfactant_out": "ppm",
          "salinity_out": "ppm"}
PROFILES = {"sw": "1", "so": "1", "sme": "1", "c_polymer": "ppm", "c_surfactant": "ppm", "salinity": "ppm",
            "pressure": "Pa"}
TOTAL_PV = {"BCF1": 1.45 + 0.50 + 1.01 + 1.27, "BCF2": 1.60 + 1.0 + 0.25 + 0.50 + 1.59,
            "BCF3": 1.60 + 0.25 + 0.25 + 0.51 + 1.49}  # thesis Table 2.5


@pytest.fixture(scope="module")
def bcf1():
    return simulate("BCF1", cells=50, pv_step=0.1, profiles_at=[0.0, 1.45, 2.5, TOTAL_PV["BCF1"]])


@pytest.mark.parametrize("name", ["BCF1", "BCF2", "BCF3"])
def test_named_schedules_run_and_grid_ends_at_total_pv(name):
    ds = simulate(name, cells=30, pv_step=0.1)
    pv = ds.pv.values
    assert pv[0] == 0.0 and pv[-1] == pytest.approx(TOTAL_PV[name], abs=1e-12)
    assert np.allclose(np.diff(pv)[:-1], 0.1)
    assert 0.0 < pv[-1] - pv[-2] <= 0.1 + 1e-12
    assert ds.attrs["schedule"] == name
    for var in SERIES:
        assert np.all(np.isfinite(ds[var].values)), var


def test_fine_grid_has_pv_step_spacing():
    ds = simulate("BCF1", cells=30)  # default pv_step 0.01
    assert ds.sizes["pv"] == 424 and ds.pv.values[-1] == pytest.approx(4.23, abs=1e-12)
    assert np.allclose(np.diff(ds.pv.values), 0.01)


def test_series_variables_units_and_long_names(bcf1):
    assert set(SERIES) <= set(bcf1.data_vars)
    for var, unit in SERIES.items():
        assert bcf1[var].dims == ("pv",)
        assert bcf1[var].attrs["units"] == unit
        assert bcf1[var].attrs["long_name"]
        assert bcf1[var].attrs["sampling"]
    assert bcf1.pv.attrs["units"] == "1"  # injected pore volumes: a volume ratio (UDUNITS reads "PV" as petavolt)


def test_profiles_layout(bcf1):
    assert list(bcf1.profile_pv.values) == pytest.approx([0.0, 1.45, 2.5, TOTAL_PV["BCF1"]])
    x = bcf1.x.values
    assert x.shape == (50,) and x[0] == pytest.approx(0.01) and x[-1] == pytest.approx(0.99)
    for var, unit in PROFILES.items():
        assert bcf1[var].dims == ("profile_pv", "x")
        assert bcf1[var].attrs["units"] == unit
    sat = bcf1.sw + bcf1.so + bcf1.sme
    assert np.allclose(sat.values, 1.0, atol=1e-12)
    assert np.all(bcf1[["sw", "so", "sme"]].to_array().values >= 0.0)
    initial = bcf1.sel(profile_pv=0.0)
    assert np.allclose(initial.sw, 0.2) and np.allclose(initial.so, 0.8)  # default SWI
    assert np.allclose(initial.salinity, 9400.0)  # Table 2.1 brine = 9 400 ppm
    # pressure falls monotonically from injector to producer and matches dp at the same time
    p = bcf1.pressure.sel(profile_pv=2.5).values
    assert np.all(np.diff(p) < 0) and p[-1] > 0
    assert bcf1.dp.sel(pv=2.5, method="nearest").item() > p[0]


def test_dataset_attrs(bcf1):
    a = bcf1.attrs
    assert a["cells"] == 50 and a["scheme"] == "tvd" and a["n_steps"] > 0 and a["wall_time_s"] > 0
    for spec in PARAMETERS:
        assert a[f"param_{spec.name}"] == spec.default
    for effect in BUILTIN_EFFECTS:
        assert a[f"effect_{effect.name}"] == effect.default_strength
    for comp in ("water", "oil", "surfactant", "polymer", "anions", "divalent"):
        assert 0.0 <= a[f"mass_balance_error_{comp}"] < 1e-10


def test_deterministic_bit_identical():
    kw = dict(cells=40, pv_step=0.05, profiles_at=[2.2])
    a = simulate("BCF2", **kw)
    b = simulate("BCF2", **kw)
    for var in a.data_vars:
        assert np.array_equal(a[var].values, b[var].values), var
    assert a.attrs["n_steps"] == b.attrs["n_steps"]


def test_recovery_monotone_bounded_and_cuts_in_range(bcf1):
    rec = bcf1.recovery.values
    assert rec[0] == 0.0 and np.all(np.diff(rec) >= -1e-15) and rec[-1] <= 1.0
    oc = bcf1.oil_cut.values
    assert np.all((oc >= 0.0) & (oc <= 1.0 + 1e-12))
    # before water breakthrough the effluent is oil (water at SWI = S1RWC is immobile, up to the small lowering of
    # S1r by the trapping number, Eq. 2.12): recovery = injected PV / OOIP
    assert rec[1] == pytest.approx(0.1 / 0.8, rel=1e-5)


def test_surfactant_polymer_slug_raises_recovery_over_waterflood():
    sp = BCF_SCHEDULES["BCF1"]
    water = Schedule(tuple(Slug(s.name, s.pv, s.salinity_ppm) for s in sp.slugs), "BCF1-water")
    with_sp = simulate(sp, cells=50, pv_step=0.1)
    no_sp = simulate(water, cells=50, pv_step=0.1)
    assert with_sp.recovery.values[14] == no_sp.recovery.values[14]  # identical up to the SP slug (1.45 PV)
    gain = with_sp.recovery.values[-1] - no_sp.recovery.values[-1]
    assert gain > 0.1, gain
    assert with_sp.c_polymer_out.max() > 0 and no_sp.c_polymer_out.max() == 0


def test_upwind_scheme_and_mapping_schedule():
    slugs = [{"pv": 0.5, "salinity_ppm": 9400.0}, {"pv": 0.5, "salinity_ppm": 9400.0, "polymer_ppm": 1000.0}]
    ds = simulate(slugs, cells=20, pv_step=0.1, scheme="upwind", cfl=0.9)
    assert ds.attrs["scheme"] == "upwind" and ds.attrs["schedule"] == "custom"
    assert ds.pv.values[-1] == pytest.approx(1.0)


def test_effects_change_the_response():
    base = simulate("BCF1", cells=30, pv_step=0.1)
    newtonian = simulate("BCF1", cells=30, pv_step=0.1, effects={"shear_thinning": 0.0})
    no_rk = simulate("BCF1", cells=30, pv_step=0.1, effects={"permeability_reduction": 0.0})
    # shear thinning lowers the polymer viscosity, permeability reduction raises the post-flush pressure drop
    assert newtonian.dp.max() > base.dp.max()
    assert base.dp.values[-1] > no_rk.dp.values[-1] * 1.05
    assert newtonian.attrs["effect_shear_thinning"] == 0.0
    assert not math.isclose(base.recovery.values[-1], simulate(
        "BCF1", cells=30, pv_step=0.1, effects={"capillary_desaturation": 0.0}).recovery.values[-1])


def test_capillary_pressure_and_kinetic_adsorption_run():
    ds = simulate("BCF1", cells=30, pv_step=0.1, effects={"capillary_pressure": 1.0, "kinetic_adsorption": 1.0})
    assert np.all(np.isfinite(ds.dp.values)) and ds.recovery.values[-1] <= 1.0
    for comp in ("water", "oil", "surfactant", "polymer", "anions", "divalent"):
        assert ds.attrs[f"mass_balance_error_{comp}"] < 1e-10
