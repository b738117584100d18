"""A homogeneous 2-D core (uniform k, ny identical rows) must reproduce the 1-D solution along x (same nx): the
pressure solve gives uniform row velocities to round-off, so every series agrees to round-off level.

The reference is the independently validated 1-D model (Buckley-Leverett, Riemann and single-phase oracles in
tests/forward), run in the same test."""

import numpy as np
import pytest

from spflow.plugins.forward.simulate import simulate

POLYMER_FLOOD = [{"pv": 0.4, "salinity_ppm": 9400.0}, {"pv": 0.5, "salinity_ppm": 17500.0, "polymer_ppm": 2000.0},
                 {"pv": 0.4, "salinity_ppm": 12000.0}]


@pytest.mark.parametrize("schedule,ny", [("BCF1", 3), (POLYMER_FLOOD, 5)])
def test_homogeneous_2d_equals_1d(schedule, ny):
    """Full SP physics (BCF1: surfactant, polymer, salinity gradient, trapping, dispersion) and a polymer flood with
    adsorption, IPV and R_k: recovery to 1e-13 absolute (measured 3e-15), the other series to 1e-9 relative (dp:
    the CG tolerance, measured 3e-11), the same steps."""
    nx = 40
    one = simulate(schedule, cells=nx, pv_step=0.05, profiles_at=[0.6])
    two = simulate(schedule, cells=(nx, ny), pv_step=0.05, profiles_at=[0.6])
    assert two.attrs["n_steps"] == one.attrs["n_steps"]
    assert two.attrs["n_pressure_iterations"] > 0  # the default iterative (PCG) pressure solve, not refactored
    assert two.attrs["n_pressure_factorizations"] < two.attrs["n_pressure_solves"] / 4  # at every solve
    assert np.max(np.abs(two.recovery.values - one.recovery.values)) < 1e-13
    for name in ("dp", "oil_cut", "c_polymer_out", "c_surfactant_out", "salinity_out"):
        scale = max(float(np.max(np.abs(one[name].values))), 1e-30)
        assert np.max(np.abs(two[name].values - one[name].values)) <= 1e-9 * scale, name
    for name in ("sw", "so", "c_polymer", "salinity"):
        ref = one[name].isel(profile_pv=0).values
        maps = two[name].isel(profile_pv=0).values
        assert maps.shape == (ny, nx)
        scale = max(float(np.max(np.abs(ref))), 1e-30)
        assert np.max(np.abs(maps - ref[None, :])) <= 1e-9 * scale, name


def test_transverse_dispersivity_and_pressure_lag_do_not_act_on_a_uniform_flow():
    """With a uniform flow along x the transverse dispersion and a lagged pressure change nothing (to round-off)."""
    nx = 30
    one = simulate(POLYMER_FLOOD, cells=nx, pv_step=0.1)
    two = simulate(POLYMER_FLOOD, cells=(nx, 4), pv_step=0.1, alpha_t_ratio=1.0, pressure_every=7)
    assert two.attrs["n_pressure_solves"] < two.attrs["n_steps"]
    assert np.max(np.abs(two.recovery.values - one.recovery.values)) < 1e-12
    assert np.max(np.abs(two.c_polymer_out.values - one.c_polymer_out.values)) < 1e-9 * 2000.0


def test_dispatch_and_output_layout():
    ds = simulate([{"pv": 0.3, "salinity_ppm": 9400.0}], cells=(12, 4), pv_step=0.1, profiles_at=[0.1, 0.3])
    assert ds.sw.dims == ("profile_pv", "y", "x") and ds.sw.shape == (2, 4, 12)
    assert ds.permeability.dims == ("y", "x") and ds.permeability.attrs["units"] == "mD"
    assert ds.dp.attrs["units"] == "Pa" and ds.pressure.attrs["units"] == "Pa"
    assert ds.attrs["nx"] == 12 and ds.attrs["ny"] == 4 and ds.attrs["n_steps"] > 0
    assert ds.attrs["wall_time_s"] > 0.0
    assert np.allclose(np.diff(ds.y.values), ds.attrs["aspect"] / 4)
