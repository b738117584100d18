"""Per-slug injection rates (``Slug.rate_ml_min``) against independent references.

* A water-filled core (SWI = 1, k_rw = 1, no permeability reduction or adsorption) at steady polymer flow, with the
  rate stepped through 0.0625-4 ml/min: the pressure drop at every rate is Darcy's law with Meter's apparent
  viscosity at UTCHEM's equivalent shear rate, ``dp = mu_app(gamma_eq(u)) u L / k`` with
  ``mu_app = mu_w + (mu_0 - mu_w) / (1 + (gamma_eq / gamma_half)^(P_alpha - 1))`` (thesis Eq. 2.4) and
  ``gamma_eq = GAMMAC u / sqrt(k k_rw phi S_w)`` (u in ft/day, k in darcy: UTCHEM field units), the zero-shear
  viscosity from Flory-Huggins with the salinity power (Eqs. 2.1-2.2) -- all written out here from the inputs
  (steady single-phase flow makes the discrete dp exact: agreement to 1e-9, issue 20 asks for 0.5 %).
* A waterflood without rate-dependent physics (no trapping-number dependence, no capillary pressure or molecular
  diffusion): recovery and oil cut versus PV do not depend on the rate (incompressible flow), and the pressure drop
  scales with it.
* Defaults unchanged: a schedule whose every slug sets ``rate_ml_min = QINJ`` gives exactly the outputs of the same
  schedule without rates.
"""

import json
import math
import tomllib
from functools import lru_cache

import numpy as np
import pytest

from spflow.core.errors import ParameterError
from spflow.io.format import schedule_json
from spflow.io.schedule_file import read_schedule_file
from spflow.plugins.forward.schedule import BCF_SCHEDULES, Schedule, Slug, as_schedule
from spflow.plugins.forward.simulate import simulate

LENGTH_M, DIAMETER_M, PORO, PERM_MD, QINJ, VIS1_CP = 0.1524, 0.0508, 0.23, 700.0, 0.25, 1.0
WATER_FILLED = {
    "SWI": 1.0, "S1RWC": 0.0, "S2RWC": 0.0, "S3RWC": 0.0, "P1RWC": 1.0, "P1RC": 1.0,
    "LENGTH": LENGTH_M, "DIAMETER": DIAMETER_M, "PORO": PORO, "PERM": PERM_MD, "QINJ": QINJ, "VIS1": VIS1_CP,
}
# polymer: Flory-Huggins with the salinity power, Meter shear thinning at a fixed half shear rate
AP1, AP2, AP3, SSLOPE, GAMMAC, GAMHF, POWN = 15.0, 0.0, 155.0, -0.76, 40.0, 60.0, 1.66
POLYMER_PPM, SALINITY_PPM = 2000.0, 9400.0
#: the Table 2.1 brine: 9400 ppm TDS holds 0.145 meq/ml of anions (docs/forward_model.md, unit conventions)
ANIONS_MEQ_ML = 0.145
FILL_PV = 4.0
RATES = (0.25, 1.0, 0.0625, 4.0, 0.5)
STEP_PV = 0.5


def meter_pressure_drop_pa(rate_ml_min: float) -> float:
    """Steady single-phase dp (Pa) of the polymer solution at ``rate_ml_min``, from the formulas."""
    c = POLYMER_PPM / 1.0e4  # wt %
    mu0 = VIS1_CP * (1.0 + (AP1 * c + AP2 * c**2 + AP3 * c**3) * ANIONS_MEQ_ML**SSLOPE)
    area = math.pi * DIAMETER_M**2 / 4.0
    u = rate_ml_min * 1.0e-6 / 60.0 / area  # m/s
    u_ft_day = u / 0.3048 * 86400.0
    gamma = GAMMAC * u_ft_day / math.sqrt(PERM_MD * 1.0e-3 * 1.0 * PORO * 1.0)  # k_rw = S_w = 1
    mu = VIS1_CP + (mu0 - VIS1_CP) / (1.0 + (gamma / GAMHF) ** (POWN - 1.0))
    return mu * 1.0e-3 * u * LENGTH_M / (PERM_MD * 9.869233e-16)


@lru_cache(maxsize=None)
def polymer_rate_steps():
    schedule = [{"name": "fill", "pv": FILL_PV, "salinity_ppm": SALINITY_PPM, "polymer_ppm": POLYMER_PPM,
                 "rate_ml_min": QINJ}]
    schedule += [{"name": f"q{k}", "pv": STEP_PV, "salinity_ppm": SALINITY_PPM, "polymer_ppm": POLYMER_PPM,
                  "rate_ml_min": q} for k, q in enumerate(RATES)]
    params = {**WATER_FILLED, "AP1": AP1, "AP2": AP2, "AP3": AP3, "SSLOPE": SSLOPE, "GAMMAC": GAMMAC,
              "GAMHF": GAMHF, "POWN": POWN, "IGAMHF": 0, "C50": ANIONS_MEQ_ML, "BETAP": 1.0}
    effects = {"polymer_adsorption": 0.0, "permeability_reduction": 0.0, "capillary_desaturation": 0.0,
               "shear_thinning": 1.0, "polymer_salinity": 1.0}
    return simulate(schedule, params, cells=50, effects=effects, pv_step=0.05)


def test_polymer_rate_steps_follow_meter_model():
    ds = polymer_rate_steps()
    pv, dp = ds["pv"].values, ds["dp"].values
    expected = np.array([meter_pressure_drop_pa(q) for q in RATES])
    # the apparent viscosity spans shear rates 15-930 1/s around GAMHF = 60 1/s: a strong test of the rate
    assert expected[3] / expected[2] < 0.5 * RATES[3] / RATES[2]
    for k, q in enumerate(RATES):
        start = FILL_PV + k * STEP_PV
        inside = (pv > start + 1.0e-9) & (pv < start + STEP_PV - 1.0e-9)
        assert inside.sum() >= 5
        np.testing.assert_allclose(dp[inside], expected[k], rtol=1.0e-9,
                                   err_msg=f"dp at {q} ml/min vs Meter/Darcy {expected[k]:.6g} Pa")
    # at a slug end the record holds the ending slug's rate (left limit)
    end0 = int(np.argmin(np.abs(pv - FILL_PV)))
    assert dp[end0] == pytest.approx(meter_pressure_drop_pa(QINJ), rel=1.0e-9)
    assert ds.attrs["slug_rate_ml_min"] == [QINJ, *RATES]


WATERFLOOD = [(0.3, 0.25), (0.4, 1.0), (0.5, 0.1), (0.8, 2.0)]
NO_RATE_PHYSICS = {"capillary_desaturation": 0.0, "capillary_pressure": 0.0}


@lru_cache(maxsize=None)
def waterflood(with_rates: bool):
    schedule = [{"pv": pv, "salinity_ppm": 9400.0} | ({"rate_ml_min": q} if with_rates else {})
                for pv, q in WATERFLOOD]
    return simulate(schedule, {"QINJ": QINJ, "DMOL": 0.0}, cells=60, effects=NO_RATE_PHYSICS, pv_step=0.01)


def test_waterflood_recovery_is_rate_independent_and_dp_scales_with_rate():
    plain, stepped = waterflood(False), waterflood(True)
    for name in ("recovery", "oil_cut"):
        np.testing.assert_allclose(stepped[name].values, plain[name].values, rtol=1e-12, atol=1e-14,
                                   err_msg=f"{name} changed with the rate")
    assert plain["recovery"].values[-1] > 0.3  # a real displacement
    pv = plain["pv"].values
    ends = np.cumsum([pv_ for pv_, _ in WATERFLOOD])
    starts = ends - np.array([pv_ for pv_, _ in WATERFLOOD])
    for (start, end), (_, q) in zip(zip(starts, ends), WATERFLOOD):
        inside = (pv > start + 1.0e-9) & (pv < end - 1.0e-9)
        np.testing.assert_allclose(stepped["dp"].values[inside], plain["dp"].values[inside] * q / QINJ, rtol=1e-12,
                                   err_msg=f"dp at {q} ml/min is not {q / QINJ:g} x dp at QINJ")


@pytest.mark.parametrize("pv_step", [0.1, 0.01, 0.001])
def test_dp_at_a_slug_end_is_the_ending_slugs(pv_step):
    """The record at a slug end is the left limit: the ending slug's rate, also where the output time and the slug
    end differ by rounding (140 x 0.01 = 1.4000000000000001 against 0.6 + 0.8 = 1.4)."""
    slugs = [(0.6, 0.25), (0.8, 0.5), (0.6, 0.125)]
    runs = [simulate([{"pv": pv_, "salinity_ppm": 9400.0} | ({"rate_ml_min": q} if rated else {}) for pv_, q in slugs],
                     {"QINJ": QINJ, "DMOL": 0.0}, cells=30, effects=NO_RATE_PHYSICS, pv_step=pv_step)
            for rated in (False, True)]
    plain, stepped = runs
    for end, (_, q), (_, q_next) in zip(np.cumsum([pv_ for pv_, _ in slugs])[:-1], slugs, slugs[1:]):
        k = int(np.argmin(np.abs(plain["pv"].values - end)))
        assert abs(plain["pv"].values[k] - end) < 1e-9
        left = plain["dp"].values[k] * q / QINJ
        assert stepped["dp"].values[k] == pytest.approx(left, rel=1e-9), (end, stepped["dp"].values[k], left,
                                                                         left * q_next / q)


@pytest.mark.parametrize("qinj", [0.25, 0.6])
def test_rates_equal_to_qinj_give_the_plain_run_exactly(qinj):
    plain = simulate("BCF1", {"QINJ": qinj}, cells=40, pv_step=0.05)
    explicit = Schedule(tuple(Slug(s.name, s.pv, s.salinity_ppm, s.surfactant_ppm, s.polymer_ppm, rate_ml_min=qinj)
                              for s in BCF_SCHEDULES["BCF1"].slugs), "BCF1")
    ds = simulate(explicit, {"QINJ": qinj}, cells=40, pv_step=0.05)
    assert set(ds.data_vars) == set(plain.data_vars)
    for name in plain.data_vars:
        assert np.array_equal(ds[name].values, plain[name].values), name
    assert "slug_rate_ml_min" not in plain.attrs


def test_rate_round_trips_through_json_and_toml(tmp_path):
    sched = as_schedule({"name": "steps", "slugs": [{"pv": 1.0, "salinity_ppm": 9400.0},
                                                    {"pv": 0.5, "salinity_ppm": 9400.0, "rate_ml_min": 1.5}]})
    text = schedule_json(sched)
    slugs = json.loads(text)["slugs"]
    assert "rate_ml_min" not in slugs[0] and slugs[1]["rate_ml_min"] == 1.5
    assert as_schedule(json.loads(text)) == sched
    path = tmp_path / "steps.toml"
    path.write_text('name = "steps"\n[[slugs]]\npv = 1.0\nsalinity_ppm = 9400\n'
                    '[[slugs]]\npv = 0.5\nsalinity_ppm = 9400\nrate_ml_min = 1.5\n')
    assert tomllib.loads(path.read_text())["slugs"][1]["rate_ml_min"] == 1.5
    assert read_schedule_file(path) == sched


@pytest.mark.parametrize("rate", [0.0, -1.0, 2.0e3, float("nan"), "fast", True])
def test_bad_rate_names_slug_and_field(rate):
    with pytest.raises(ParameterError, match=r"slug 1 \('P'\): field 'rate_ml_min'.*\[0.0001, 1000\]"):
        as_schedule([{"name": "W", "pv": 1.0, "salinity_ppm": 9400.0},
                     {"name": "P", "pv": 1.0, "salinity_ppm": 9400.0, "rate_ml_min": rate}])


def test_two_d_rejects_rate_steps():
    schedule = [{"name": "W", "pv": 0.5, "salinity_ppm": 9400.0, "rate_ml_min": 1.0}]
    with pytest.raises(ParameterError, match=r"slug 0 \('W'\): field 'rate_ml_min'.*2-D"):
        simulate(schedule, cells=(10, 3))


def test_every_rate_dependent_term_takes_the_slug_rate():
    """QINJ enters the model only through the Darcy velocity and the time per PV, so a run whose every slug sets
    ``rate_ml_min = q`` must be the run at ``QINJ = q`` -- with shear thinning, the trapping number, capillary
    pressure and kinetic adsorption all on; a term still reading QINJ would break the equality."""
    on = {"capillary_pressure": 1.0, "kinetic_adsorption": 1.0, "capillary_desaturation": 1.0, "shear_thinning": 1.0}
    params = {"QINJ": 0.25, "DMOL": 1.0e-9}
    slugs = BCF_SCHEDULES["BCF1"].slugs
    at_rate = Schedule(tuple(Slug(s.name, s.pv, s.salinity_ppm, s.surfactant_ppm, s.polymer_ppm, rate_ml_min=1.0)
                             for s in slugs), "BCF1")
    ds = simulate(at_rate, params, cells=30, pv_step=0.05, effects=on)
    ref = simulate("BCF1", {**params, "QINJ": 1.0}, cells=30, pv_step=0.05, effects=on)
    low = simulate("BCF1", params, cells=30, pv_step=0.05, effects=on)
    for name in ref.data_vars:
        assert np.array_equal(ds[name].values, ref[name].values), name
    assert not np.allclose(low["recovery"].values, ref["recovery"].values, rtol=1e-6)  # the rate matters here
