"""Capillary-desaturation fit (thesis section 2.8, Eq. 2.12, Fig. 2.8): model against the equation written out here,
recovery for each phase, the delta-method covariance of T, coverage, the stage on the bundled table, located
errors, the figure."""

import tomllib

import numpy as np
import pytest
from fit_coverage import coverage

from spflow.core.stage import StageContext
from spflow.plugins.forward.parameters import default_params
from spflow.plugins.lab.desaturation_fit import (
    desaturation_model,
    fit_desaturation,
    phase_names,
    read_desaturation_table,
    synthetic_desaturation,
)
from spflow.plugins.lab.fit_result import FIT, FitError, fit_interval
from spflow.plugins.lab.surfactant_fit_figures import desaturation_figure
from spflow.plugins.lab.polymer_fit_stages import LAB_DIR
from spflow.plugins.lab.surfactant_fit_stages import FitDesaturation
from spflow.plugins.lab.lab_table import write_lab_table

TRUTH = {**default_params(), "S2RC": 0.05, "S1RC": 0.03, "S3RC": 0.02}
NUMBER = np.geomspace(1e-7, 1e-1, 16)


def test_model_is_eq_2_12_with_tau_1():
    n = np.geomspace(1e-8, 1.0, 9)
    expected = 0.05 + (0.3 - 0.05) / (1 + 1100.0 * n)
    np.testing.assert_allclose(desaturation_model(n, 1100.0, 0.3, 0.05), expected, rtol=1e-13)


@pytest.mark.parametrize("phase", [1, 2, 3])
def test_noise_free_recovery(phase):
    fit = fit_desaturation(synthetic_desaturation(TRUTH, NUMBER, phase=phase, noise=0.0))
    names = phase_names(phase)
    assert list(fit["param"].values) == list(names)
    np.testing.assert_allclose(fit["estimate"].values, [TRUTH[n] for n in names], rtol=1e-6)


def test_t_covariance_is_the_delta_method_of_log10_t():
    fit = fit_desaturation(synthetic_desaturation(TRUTH, NUMBER, noise=0.01, seed=4))
    t = float(fit["estimate"].sel(param="T22"))
    assert t == pytest.approx(10 ** fit.attrs["log10_t_estimate"], rel=1e-12)
    assert float(fit["std"].sel(param="T22")) == pytest.approx(t * np.log(10) * fit.attrs["log10_t_std"], rel=1e-12)
    cov = fit["covariance"].values
    np.testing.assert_allclose(cov, cov.T, rtol=1e-12)
    assert np.all(np.linalg.eigvalsh(cov) > 0)


def test_coverage_over_seeds():
    inside, spread, names = coverage(lambda seed: synthetic_desaturation(TRUTH, NUMBER, noise=0.01, seed=seed),
                                     fit_desaturation, TRUTH)
    assert names == ["T22", "S2RWC", "S2RC"]
    assert all(count >= 16 for count in inside.values()), inside
    assert all(0.5 < ratio < 1.6 for ratio in spread.values()), spread


def test_stage_on_bundled_table_brackets_truth(tmp_path):
    truth = tomllib.loads((LAB_DIR / "surfactant_truth.toml").read_text())["desaturation"]["truth"]
    stage = FitDesaturation()
    stage.fingerprint()
    fit = stage.run(StageContext("cdc"))
    FIT.validate(fit, stage="fit_desaturation", port="output")
    lo, hi = fit_interval(fit)
    for name, value in truth.items():
        assert float(lo.sel(param=name)) <= value <= float(hi.sel(param=name)), name
    assert desaturation_figure(fit, tmp_path / "fig_2_8.png").stat().st_size > 10_000


def test_located_errors(tmp_path):
    data = synthetic_desaturation(TRUTH, NUMBER, noise=0.0)
    bad = data.copy(deep=True)
    bad["capillary_number"][3] = -1e-5
    with pytest.raises(FitError, match="'capillary_number' must be > 0; data row 4 has -1e-05"):
        read_desaturation_table(write_lab_table(bad, tmp_path / "bad.csv", "desaturation"))
    phase = data.copy()
    phase.attrs["meta_phase"] = "4"
    with pytest.raises(FitError, match="'phase': 4.0 must be 1 \\(aqueous\\)"):
        read_desaturation_table(write_lab_table(phase, tmp_path / "phase.csv", "desaturation"))
    few = data.isel(point=[0, 0, 1, 1, 2])
    with pytest.raises(FitError, match="at least 4 distinct capillary numbers"):
        fit_desaturation(few)
