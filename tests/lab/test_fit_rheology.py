"""Polymer rheology fit (Eqs. 2.1-2.5): model vs the hand values of docs/forward_model.md, exact recovery, coverage
over seeds, errors."""

import tomllib

import numpy as np
import pytest

from spflow.core.stage import StageContext
from spflow.plugins.forward.parameters import default_params
from spflow.plugins.lab import polymer_rheology as pr
from spflow.plugins.lab.fit_result import FIT, FitError, fit_interval
from spflow.plugins.lab.polymer_fit_figures import half_shear_rate_figure, polymer_rheology_figure
from spflow.plugins.lab.polymer_fit_stages import LAB_DIR, FitPolymerRheology
from spflow.plugins.lab.lab_table import LabDataError

TRUTH = {n: default_params()[n] for n in pr.NAMES}
CTX = StageContext("lab", verbose=False)


def test_model_matches_physics_notes_flory_huggins_and_meter_values():
    # docs/forward_model.md, Property values: Cp 0.1 wt%, C_SEP 0.2, AP 20/300/2000, SSLOPE -0.3, mu_w 0.8 -> mu0
    # 9.8757 cP; GAMHF 10 1/s,
    # POWN 1.8 -> 8.6341/5.3378/2.0416/1.0224 cP at 1/10/100/1000 1/s. Eq. 2.5 with A0 = 10, A1 = A2 = 0 is GAMHF 10.
    theta = {"AP1": 20.0, "AP2": 300.0, "AP3": 2000.0, "SSLOPE": -0.3, "BETAP": 1.0, "POWN": 1.8,
             "A0": 10.0, "A1": 0.0, "A2": 0.0}
    mu = pr.rheology_viscosity(theta, 0.1, 0.2, 0.0, np.array([0.0, 1.0, 10.0, 100.0, 1000.0]), 0.8, 1e-4)
    np.testing.assert_allclose(mu, [9.8757, 8.6341, 5.3378, 2.0416, 1.0224], atol=6e-5)
    # BETAP weights the divalent cations: C_SEP = C51 + (BETAP - 1) C61
    hard = pr.rheology_viscosity(dict(theta, BETAP=3.0), 0.1, 0.1, 0.05, 0.0, 0.8, 1e-4)
    assert hard == pytest.approx(mu[0], rel=1e-12)


def test_noise_free_data_recover_the_truth():
    fit = pr.fit_rheology(pr.synthetic_rheology(TRUTH, None))
    est = dict(zip(fit["param"].values, fit["estimate"].values))
    for name, value in TRUTH.items():
        assert est[name] == pytest.approx(value, rel=1e-6, abs=1e-6), name
    FIT.validate(fit, stage="fit_polymer_rheology", port="output")


def test_truth_inside_95_percent_interval_over_seeds():
    hits = dict.fromkeys(pr.NAMES, 0)
    n_seeds = 20
    for seed in range(n_seeds):
        fit = pr.fit_rheology(pr.synthetic_rheology(TRUTH, np.random.default_rng(1000 + seed)))
        lo, hi = fit_interval(fit, 0.95)
        for name in pr.NAMES:
            hits[name] += bool(lo.sel(param=name) <= TRUTH[name] <= hi.sel(param=name))
    assert all(h >= 16 for h in hits.values()), hits


def test_stage_on_bundled_data_and_figures(tmp_path):
    fit = FitPolymerRheology().run(CTX)
    truth = tomllib.loads((LAB_DIR / "polymer_truth.toml").read_text())["truth"]
    for name in pr.NAMES:  # a 3.5-sigma check on the bundled seed (could fail only with a broken fit)
        est, std = float(fit["estimate"].sel(param=name)), float(fit["std"].sel(param=name))
        assert abs(est - truth[name]) <= 3.5 * std, (name, est, std)
    assert fit.sizes["sweep"] == len(pr.DESIGN_CP) * len(pr.DESIGN_BRINES)
    for draw, name in ((polymer_rheology_figure, "fig2_2.png"), (half_shear_rate_figure, "fig2_3.png")):
        path = draw(fit, tmp_path / name)
        assert path.stat().st_size > 10_000


def test_bad_lab_data_raise(tmp_path):
    ds = pr.synthetic_rheology(TRUTH, None)
    del ds.attrs["meta_water_viscosity"]
    with pytest.raises(LabDataError, match="water_viscosity"):
        pr.fit_rheology(ds)
    ds = pr.synthetic_rheology(TRUTH, None, mu_w=1.0)
    ds.attrs["meta_water_viscosity"] = "50 cP"
    with pytest.raises(FitError, match="exceed water_viscosity"):
        pr.fit_rheology(ds)
    with pytest.raises(Exception, match="no such file"):
        FitPolymerRheology(path=str(tmp_path / "missing.csv")).run(CTX)


def test_stage_cache_key_follows_file_content(tmp_path):
    bundled = LAB_DIR / "polymer_rheology.csv"
    copy = tmp_path / "copy.csv"
    copy.write_text(bundled.read_text())
    assert FitPolymerRheology(path=str(copy)).fingerprint() == FitPolymerRheology().fingerprint()
    copy.write_text(bundled.read_text().replace("# water_viscosity: 1 cP", "# water_viscosity: 1.01 cP"))
    assert FitPolymerRheology(path=str(copy)).fingerprint() != FitPolymerRheology().fingerprint()
