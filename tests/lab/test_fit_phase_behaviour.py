"""Phase-behaviour fit (Hand's rule, thesis section 2.5, Fig. 2.5): model against closed forms, recovery, coverage,
the stage on the bundled table, located errors, the figure."""

import tomllib

import numpy as np
import pytest
from fit_coverage import coverage

from spflow.core.errors import ParameterError
from spflow.core.stage import StageContext
from spflow.plugins.forward.parameters import default_params
from spflow.plugins.lab.fit_result import FIT, FitError, fit_interval
from spflow.plugins.lab.surfactant_fit_figures import phase_behaviour_figure
from spflow.plugins.lab.polymer_fit_stages import LAB_DIR
from spflow.plugins.lab.surfactant_fit_stages import FitPhaseBehaviour
from spflow.plugins.lab.lab_table import LabDataError, write_lab_table
from spflow.plugins.lab.phase_behaviour_fit import (
    NAMES,
    fit_phase_behaviour,
    read_pipette_tests,
    solubilization_curve,
    synthetic_pipette_tests,
)

TRUTH = default_params()
SALINITY = np.r_[np.arange(0.05, 0.551, 0.05), np.arange(0.26, 0.301, 0.005)]
Z3 = 0.00678


def _hand_a(c3max):
    return (2 * c3max / (1 - c3max)) ** 2


def test_ratios_match_hand_closed_forms():
    """Type II(-): all water in the ME, R23 = z3/(A z1); optimum: R = (1 - C3max1)/(2 C3max1); type II(+): mirror.
    A from the linear-in-salinity interpolation of the three binodal heights, computed here."""
    csel, cseu, c0, c1, c2 = theta = [0.2, 0.3, 0.03, 0.015, 0.022]
    z1 = z2 = (1 - Z3) / 2
    cseop = 0.5 * (csel + cseu)
    low, high = np.array([0.05, 0.15]), np.array([0.35, 0.45])
    a_low = (_hand_a(c0) - _hand_a(c1)) * (1 - low / cseop) + _hand_a(c1)
    a_high = (_hand_a(c2) - _hand_a(c1)) * (high / cseop - 1) + _hand_a(c1)
    r13, r23 = solubilization_curve(np.r_[low, cseop, high], theta, surfactant=Z3)
    np.testing.assert_allclose(r13[:2], z1 / Z3, rtol=1e-12)
    np.testing.assert_allclose(r23[:2], Z3 / (a_low * z1), rtol=1e-10)
    np.testing.assert_allclose([r13[2], r23[2]], (1 - c1) / (2 * c1), rtol=1e-10)
    np.testing.assert_allclose(r23[3:], z2 / Z3, rtol=1e-12)
    np.testing.assert_allclose(r13[3:], Z3 / (a_high * z2), rtol=1e-10)


@pytest.mark.parametrize("truth", [
    {n: TRUTH[n] for n in NAMES},
    {"CSEL": 0.4, "CSEU": 0.5, "HBNC70": 0.04, "HBNC71": 0.02, "HBNC72": 0.03},
])
def test_noise_free_recovery(truth):
    salinity = SALINITY * (truth["CSEL"] + truth["CSEU"]) / 0.56  # the scan centred on this optimum
    fit = fit_phase_behaviour(synthetic_pipette_tests(truth, salinity, noise=0.0))
    np.testing.assert_allclose(fit["estimate"].values, [truth[n] for n in NAMES], rtol=1e-6)
    assert fit.attrs["rss"] < 1e-20


def test_coverage_over_seeds():
    inside, spread, names = coverage(lambda seed: synthetic_pipette_tests(TRUTH, SALINITY, noise=0.05, seed=seed),
                                     fit_phase_behaviour, TRUTH)
    assert names == list(NAMES)
    assert all(count >= 16 for count in inside.values()), inside
    assert all(0.5 < ratio < 1.6 for ratio in spread.values()), spread


def test_stage_on_bundled_table_brackets_truth(tmp_path):
    truth = tomllib.loads((LAB_DIR / "surfactant_truth.toml").read_text())["phase_behaviour"]["truth"]
    stage = FitPhaseBehaviour()
    stage.fingerprint()
    fit = stage.run(StageContext("pb"))
    FIT.validate(fit, stage="fit_phase_behaviour", port="output")
    lo, hi = fit_interval(fit)
    for name, value in truth.items():
        assert float(lo.sel(param=name)) <= value <= float(hi.sel(param=name)), name
    assert fit["curve_r_water"].dims == ("curve_salinity",)
    png = phase_behaviour_figure(fit, tmp_path / "fig_2_5.png")
    assert png.stat().st_size > 10_000


def test_fingerprint_follows_content_not_path(tmp_path):
    data = synthetic_pipette_tests(TRUTH, SALINITY, noise=0.05, seed=3)
    a = write_lab_table(data, tmp_path / "a.csv", "phase_behaviour")
    b = write_lab_table(data, tmp_path / "b.csv", "phase_behaviour")
    assert FitPhaseBehaviour(path=str(a)).fingerprint() == FitPhaseBehaviour(path=str(b)).fingerprint()
    data["r_oil"][0] = 99.0
    write_lab_table(data, b, "phase_behaviour")
    assert FitPhaseBehaviour(path=str(a)).fingerprint() != FitPhaseBehaviour(path=str(b)).fingerprint()


def test_located_errors(tmp_path):
    with pytest.raises(ParameterError, match="no such lab table"):
        FitPhaseBehaviour(path=str(tmp_path / "missing.csv"))
    data = synthetic_pipette_tests(TRUTH, SALINITY, noise=0.0)
    no_meta = data.copy()
    del no_meta.attrs["meta_surfactant"]
    path = write_lab_table(no_meta, tmp_path / "no_meta.csv", "phase_behaviour")
    with pytest.raises(LabDataError, match="'surfactant': missing"):
        read_pipette_tests(path)
    bad = data.copy()
    bad.attrs["meta_surfactant"] = "1.5 fraction"
    with pytest.raises(FitError, match="surfactant volume fraction 1.5 must be in"):
        read_pipette_tests(write_lab_table(bad, tmp_path / "bad.csv", "phase_behaviour"))
    one_type = data.isel(point=slice(0, 5))  # all tubes below CSEL: the optimum is not bracketed
    with pytest.raises(FitError, match="never cross"):
        fit_phase_behaviour(one_type)
