"""Chun-Huh IFT fit (thesis section 2.6, Eqs. 2.9-2.10, Fig. 2.6): model against the equations written out here,
recovery, coverage, the stage on the bundled table, located errors, the figure."""

import tomllib

import numpy as np
import pytest
from fit_coverage import coverage

from spflow.core.stage import StageContext
from spflow.plugins.forward.parameters import default_params
from spflow.plugins.lab.fit_result import FIT, FitError, fit_interval
from spflow.plugins.lab.ift_fit import NAMES, fit_ift, ift_model, read_ift_table, synthetic_ift_table
from spflow.plugins.lab.surfactant_fit_figures import ift_figure
from spflow.plugins.lab.polymer_fit_stages import LAB_DIR
from spflow.plugins.lab.surfactant_fit_stages import FitIFT
from spflow.plugins.lab.lab_table import LabDataError, write_lab_table

TRUTH = default_params()
SALINITY = np.arange(0.05, 0.551, 0.05)
SURFACTANT = (2e-4, 5e-4, 1e-3, 3e-3, 6.78e-3)


def test_model_is_eqs_2_9_2_10():
    r13 = np.array([0.3, 5.0, 20.0, 2.0])
    r23 = np.array([0.1, 7.0, 20.0, 0.5])
    interface = np.array([1, 2, 1, 2])
    c, a, sigma_ow = 0.25, 12.0, 10**1.32
    c33 = 1 / (1 + r13 + r23)
    me = np.stack([r13 * c33, r23 * c33, c33], axis=1)
    excess = np.where(interface[:, None] == 1, [1.0, 0.0, 0.0], [0.0, 1.0, 0.0])
    f = (1 - np.exp(-np.sqrt(((excess - me) ** 2).sum(axis=1)))) / (1 - np.exp(-np.sqrt(2)))
    r = np.where(interface == 1, r13, r23)
    expected = sigma_ow * np.exp(-a * r) + c * f / r**2 * (1 - np.exp(-a * r**3))
    np.testing.assert_allclose(ift_model(interface, r13, r23, c, a, sigma_ow), expected, rtol=1e-12)


@pytest.mark.parametrize("chuh, ahuh", [(0.3, 10.0), (0.15, 18.0)])
def test_noise_free_recovery(chuh, ahuh):
    truth = {**TRUTH, "CHUH": chuh, "AHUH": ahuh}
    fit = fit_ift(synthetic_ift_table(truth, SALINITY, SURFACTANT, noise=0.0))
    np.testing.assert_allclose(fit["estimate"].values, [chuh, ahuh], rtol=1e-6)


def test_coverage_over_seeds():
    inside, spread, names = coverage(
        lambda seed: synthetic_ift_table(TRUTH, SALINITY, SURFACTANT, noise=0.08, seed=seed), fit_ift, TRUTH)
    assert names == list(NAMES)
    assert all(count >= 16 for count in inside.values()), inside
    assert all(0.5 < ratio < 1.6 for ratio in spread.values()), spread


def test_stage_on_bundled_table_brackets_truth(tmp_path):
    truth = tomllib.loads((LAB_DIR / "surfactant_truth.toml").read_text())["ift"]["truth"]
    stage = FitIFT()
    stage.fingerprint()
    fit = stage.run(StageContext("ift"))
    FIT.validate(fit, stage="fit_ift", port="output")
    lo, hi = fit_interval(fit)
    for name, value in truth.items():
        assert float(lo.sel(param=name)) <= value <= float(hi.sel(param=name)), name
    assert ift_figure(fit, tmp_path / "fig_2_6.png").stat().st_size > 10_000


def test_located_errors(tmp_path):
    data = synthetic_ift_table(TRUTH, SALINITY, SURFACTANT, noise=0.0)
    bad = data.copy(deep=True)
    bad["interface"][4] = 3.0
    with pytest.raises(FitError, match="'interface' must be 1 .* data row 5 has 3$"):
        read_ift_table(write_lab_table(bad, tmp_path / "bad.csv", "ift"))
    negative = data.copy(deep=True)
    negative["ift"][2] = -1.0
    with pytest.raises(FitError, match="'ift' must be > 0; data row 3 has -1"):
        read_ift_table(write_lab_table(negative, tmp_path / "neg.csv", "ift"))
    no_meta = data.copy()
    del no_meta.attrs["meta_xiftw"]
    with pytest.raises(LabDataError, match="'xiftw': missing"):
        read_ift_table(write_lab_table(no_meta, tmp_path / "meta.csv", "ift"))
    one_ratio = data.isel(point=[0, 0, 0, 0])
    with pytest.raises(FitError, match="at least 3 distinct"):
        fit_ift(one_ratio)
