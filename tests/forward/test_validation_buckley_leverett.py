"""Forward model vs Buckley-Leverett/Welge (Buckley & Leverett 1942; Welge 1952; test ladder step 2; thesis Figs.
1.6-1.7).

Cases: the three viscosity ratios of thesis Fig. 1.7 (mu_o/mu_w = 0.5, 1, 2; k_r° = 1, n = 2, no residuals) and a
Corey case with residuals (S_wc = 0.2, S_or = 0.3, n_w = 2.5, n_o = 2, mu_o/mu_w = 13.8). Water is injected at the
initial brine salinity with no chemicals, capillary pressure, dispersion or desaturation, so the simulator solves
exactly the Buckley-Leverett problem. The references come from :mod:`oracles` (never from the simulator).
"""

from functools import lru_cache

import numpy as np
import pytest

from oracles import (
    CoreyFractionalFlow,
    buckley_leverett,
    corey_params,
    crossing_time,
    interval_midpoints,
    l1_error,
    observed_order,
    welge_front_saturation,
)
from spflow.plugins.forward.simulate import simulate

FIG_1_7 = {f"mu_r={r}": CoreyFractionalFlow(mu_o=r) for r in (0.5, 1.0, 2.0)}
RESIDUAL = CoreyFractionalFlow(swc=0.2, sor=0.3, krw0=0.3, kro0=0.8, nw=2.5, no=2.0, mu_w=1.0, mu_o=13.8)
CASES = {**FIG_1_7, "residual": RESIDUAL}
WATERFLOOD_ONLY = {"capillary_desaturation": 0.0, "dispersion": 0.0, "capillary_pressure": 0.0}
BRINE_PPM = 9400.0  # the initial-brine salinity (parameter C50 default), so nothing but water moves
PROFILE_FRACTION = 0.6  # profile taken when the front has crossed 60 % of the core


def breakthrough_pv(flux) -> float:
    return 1.0 / buckley_leverett(flux).shock_speeds()[-1]


@lru_cache(maxsize=None)
def run(case: str):
    """400-cell TVD run to 2.5 breakthrough PV with fine output (breakthrough, N_p) and one profile."""
    flux = CASES[case]
    t_bt = breakthrough_pv(flux)
    return simulate(
        [{"pv": 2.5 * t_bt, "salinity_ppm": BRINE_PPM}],
        corey_params(flux),
        cells=400,
        effects=WATERFLOOD_ONLY,
        pv_step=0.002,
        profiles_at=[PROFILE_FRACTION * t_bt],
    )


@lru_cache(maxsize=None)
def profile_error(case: str, cells: int, scheme: str = "tvd") -> float:
    """L1 error of the profile at 60 % of breakthrough from a run that stops there (no intermediate outputs, so
    the time steps are the scheme's own CFL steps)."""
    flux = CASES[case]
    t_d = PROFILE_FRACTION * breakthrough_pv(flux)
    ds = simulate(
        [{"pv": t_d, "salinity_ppm": BRINE_PPM}], corey_params(flux), cells=cells, effects=WATERFLOOD_ONLY,
        scheme=scheme, pv_step=t_d, profiles_at=[t_d],
    )
    np.testing.assert_allclose(ds["x"].values, (np.arange(cells) + 0.5) / cells, rtol=0, atol=1e-12)
    assert float(ds["profile_pv"][0]) == t_d
    return l1_error(ds["sw"].isel(profile_pv=0).values, buckley_leverett(flux).cell_averages(t_d, cells))


@pytest.mark.parametrize("case", list(CASES))
def test_breakthrough_pv_within_one_percent_at_400_cells(case):
    flux = CASES[case]
    t_bt = breakthrough_pv(flux)
    ds = run(case)
    water_cut = 1.0 - ds["oil_cut"].values
    f_front = float(flux.fw(welge_front_saturation(flux, flux.swc)))
    # breakthrough = mid-height of the outlet water-cut jump 0 -> f(S_f)
    t_sim = crossing_time(interval_midpoints(ds["pv"].values), water_cut, 0.5 * f_front)
    assert abs(t_sim / t_bt - 1.0) < 0.01, f"{case}: simulated BT {t_sim:.4f} PV vs Welge {t_bt:.4f} PV"


@pytest.mark.parametrize("case", list(CASES))
def test_saturation_profile_l1_error_at_400_cells(case):
    # 400 cells: a TVD shock is smeared over ~3 cells, so |jump| * 3/400 <= 0.006 bounds the shock's share
    ds, flux = run(case), CASES[case]
    t_d = float(ds["profile_pv"][0])
    err = l1_error(ds["sw"].isel(profile_pv=0).values, buckley_leverett(flux).cell_averages(t_d, 400))
    assert err < 0.006, f"{case}: L1 error {err:.5f}"


@pytest.mark.parametrize("case", list(CASES))
def test_cumulative_oil_follows_welge(case):
    flux = CASES[case]
    fan = buckley_leverett(flux)
    t_bt = breakthrough_pv(flux)
    ds = run(case)
    times = np.array([0.5, 0.9, 1.3, 2.0, 2.4]) * t_bt
    n_p_sim = np.interp(times, ds["pv"].values, ds["recovery"].values) * (1.0 - flux.swc)  # fraction OOIP -> PV
    n_p_exact = fan.cumulative_oil(times)
    np.testing.assert_allclose(n_p_sim, n_p_exact, rtol=0.01, err_msg=f"{case}: N_p(t) vs Welge")
    # before breakthrough every injected PV displaces one PV of oil: a conservation check to round-off level
    assert n_p_sim[0] == pytest.approx(times[0], rel=1e-3)


@pytest.mark.parametrize("case", list(CASES))
def test_grid_refinement_converges_and_tvd_beats_upwind(case):
    cells = (50, 100, 200, 400)
    tvd = [profile_error(case, n) for n in cells]
    upwind = [profile_error(case, n, "upwind") for n in cells]
    report = f"{case}: L1 TVD {np.round(tvd, 5)}, upwind {np.round(upwind, 5)}"
    assert all(coarse > fine for coarse, fine in zip(tvd, tvd[1:])), f"TVD errors not decreasing; {report}"
    order = observed_order(cells, tvd)
    assert order >= 0.5, f"observed TVD order {order:.2f}; {report}"
    assert all(t < u for t, u in zip(tvd, upwind)), f"TVD not more accurate than upwind; {report}"
