"""Microemulsion-viscosity fit (thesis section 2.7, Eq. 2.11, Fig. 2.7): model against the equation written out
here, recovery (two and all five ALPHAVs), coverage, the stage on the bundled table, located errors, the figure."""

import tomllib

import numpy as np
import pytest
from fit_coverage import coverage

from spflow.core.errors import ParameterError
from spflow.core.stage import StageContext
from spflow.plugins.forward.parameters import default_params
from spflow.plugins.lab.fit_result import FIT, FitError, fit_interval
from spflow.plugins.lab.surfactant_fit_figures import me_viscosity_figure
from spflow.plugins.lab.polymer_fit_stages import LAB_DIR
from spflow.plugins.lab.surfactant_fit_stages import FitMEViscosity
from spflow.plugins.lab.lab_table import write_lab_table
from spflow.plugins.lab.me_viscosity_fit import (
    NAMES,
    fit_me_viscosity,
    read_me_viscosity_table,
    synthetic_me_viscosity,
    viscosity_model,
)

TRUTH = default_params()
OIL = np.linspace(0.05, 0.95, 10)
SURFACTANT = (0.02, 0.05, 0.1, 0.2, 0.3)


def test_model_is_eq_2_11():
    c1, c2, c3 = np.array([0.7, 0.2, 0.45]), np.array([0.25, 0.6, 0.45]), np.array([0.05, 0.2, 0.1])
    a = [1.5, 2.5, 3.0, 0.9, 0.7]
    mu_w, mu_o = 0.9, 12.0
    expected = (c1 * mu_w * np.exp(a[0] * (c2 + c3)) + c2 * mu_o * np.exp(a[1] * (c1 + c3))
                + c3 * a[2] * np.exp(a[3] * c1 + a[4] * c2))
    np.testing.assert_allclose(viscosity_model(c1, c2, c3, a, mu_w, mu_o), expected, rtol=1e-12)


def test_noise_free_recovery_two_and_five_parameters():
    fit = fit_me_viscosity(synthetic_me_viscosity(TRUTH, OIL, SURFACTANT, noise=0.0), fit=("ALPHAV1", "ALPHAV2"))
    np.testing.assert_allclose(fit["estimate"].values, [TRUTH["ALPHAV1"], TRUTH["ALPHAV2"]], rtol=1e-6)
    # with a surfactant term (ALPHAV3 > 0) all five are identifiable from noise-free data
    truth = {**TRUTH, "ALPHAV1": 1.2, "ALPHAV2": 2.6, "ALPHAV3": 4.0, "ALPHAV4": 1.5, "ALPHAV5": 0.4}
    fit = fit_me_viscosity(synthetic_me_viscosity(truth, OIL, SURFACTANT, noise=0.0))
    np.testing.assert_allclose(fit["estimate"].values, [truth[n] for n in NAMES], rtol=1e-5)


def test_fixed_values_are_used():
    truth = {**TRUTH, "ALPHAV3": 2.0}
    data = synthetic_me_viscosity(truth, OIL, SURFACTANT, noise=0.0)
    fit = fit_me_viscosity(data, fit=("ALPHAV1", "ALPHAV2"), fixed={"ALPHAV3": 2.0})
    np.testing.assert_allclose(fit["estimate"].values, [truth["ALPHAV1"], truth["ALPHAV2"]], rtol=1e-6)
    wrong = fit_me_viscosity(data, fit=("ALPHAV1", "ALPHAV2"))  # ALPHAV3 held at the default 0: a worse fit
    assert wrong.attrs["rss"] > 1e6 * max(fit.attrs["rss"], 1e-30)


def test_coverage_over_seeds():
    inside, spread, names = coverage(
        lambda seed: synthetic_me_viscosity(TRUTH, OIL, SURFACTANT, noise=0.04, seed=seed),
        lambda data: fit_me_viscosity(data, fit=("ALPHAV1", "ALPHAV2")), TRUTH)
    assert names == ["ALPHAV1", "ALPHAV2"]
    assert all(count >= 16 for count in inside.values()), inside
    assert all(0.5 < ratio < 1.6 for ratio in spread.values()), spread


def test_stage_on_bundled_table_brackets_truth(tmp_path):
    truth = tomllib.loads((LAB_DIR / "surfactant_truth.toml").read_text())["me_viscosity"]["truth"]
    stage = FitMEViscosity()
    stage.fingerprint()
    fit = stage.run(StageContext("mev"))
    FIT.validate(fit, stage="fit_me_viscosity", port="output")
    assert list(fit["param"].values) == list(truth)
    lo, hi = fit_interval(fit)
    for name, value in truth.items():
        assert float(lo.sel(param=name)) <= value <= float(hi.sel(param=name)), name
    assert me_viscosity_figure(fit, tmp_path / "fig_2_7.png").stat().st_size > 10_000


def test_located_errors(tmp_path):
    with pytest.raises(ParameterError, match="'fit'.*'ALPHAV9' is not allowed"):
        FitMEViscosity(fit=["ALPHAV9"])
    data = synthetic_me_viscosity(TRUTH, OIL, SURFACTANT, noise=0.0)
    bad = data.copy(deep=True)
    bad["oil"][6] = 0.9
    with pytest.raises(FitError, match="data row 7: water \\+ oil \\+ surfactant"):
        read_me_viscosity_table(write_lab_table(bad, tmp_path / "bad.csv", "me_viscosity"))
    with pytest.raises(FitError, match="fit must be a non-empty list"):
        fit_me_viscosity(data, fit=())
    with pytest.raises(FitError, match="fixed: 'ALPHAV1' is not an ALPHAV held fixed"):
        fit_me_viscosity(data, fit=("ALPHAV1",), fixed={"ALPHAV1": 1.0})
