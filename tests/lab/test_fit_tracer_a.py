"""Tracer / conductivity fit (Fig. 2.9): Ogata-Banks vs the test oracle and physics.md, recovery, coverage, errors."""

import numpy as np
import pytest

from oracles import ogata_banks
from spflow.core.stage import StageContext
from spflow.plugins.lab import tracer_fit as tf
from spflow.plugins.lab.fit_result import FIT, FitError, fit_interval
from spflow.plugins.lab.lab_figures_a import tracer_figure
from spflow.plugins.lab.lab_stages_a import FitTracer

TRUTH = {"ALPHAL1": 0.01, "TDS_PER_EC": 600.0}
CTX = StageContext("lab", verbose=False)


def test_outlet_solution_matches_oracle_and_physics_notes():
    t = np.array([0.9, 1.0, 1.1, 1.2])
    np.testing.assert_allclose(tf.ogata_banks_outlet(t, 200.0), [0.1573, 0.5199, 0.8424, 0.9698], atol=1e-4)
    t = np.linspace(0.05, 3.0, 60)
    for pe in (5.0, 50.0, 300.0):
        np.testing.assert_allclose(tf.ogata_banks_outlet(t, pe), ogata_banks(1.0, t, pe), rtol=1e-10, atol=1e-14)
    big = tf.ogata_banks_outlet(t, 5000.0)  # exp(Pe) alone would overflow
    assert np.all(np.isfinite(big)) and big[0] == 0.0 and big[-1] == pytest.approx(1.0)


def test_noise_free_data_recover_the_truth():
    fit = tf.fit_tracer(*tf.synthetic_tracer(TRUTH, None))
    np.testing.assert_allclose(fit["estimate"].values, [TRUTH[n] for n in tf.NAMES], rtol=1e-7)
    assert fit.attrs["peclet"] == pytest.approx(0.1524 / (0.01 * 0.3048))
    FIT.validate(fit, stage="fit_tracer", port="output")


def test_truth_inside_95_percent_interval_over_seeds():
    hits = dict.fromkeys(tf.NAMES, 0)
    for seed in range(20):
        fit = tf.fit_tracer(*tf.synthetic_tracer(TRUTH, np.random.default_rng(4000 + seed)))
        lo, hi = fit_interval(fit, 0.95)
        for name in tf.NAMES:
            hits[name] += bool(lo.sel(param=name) <= TRUTH[name] <= hi.sel(param=name))
    assert all(h >= 16 for h in hits.values()), hits


def test_stage_on_bundled_data_and_figure(tmp_path):
    fit = FitTracer().run(CTX)
    for name in tf.NAMES:
        est, std = float(fit["estimate"].sel(param=name)), float(fit["std"].sel(param=name))
        assert abs(est - TRUTH[name]) <= 3.5 * std, (name, est, std)
    assert tracer_figure(fit, tmp_path / "fig2_9.png").stat().st_size > 10_000


def test_no_salinity_step_raises():
    effluent, calibration = tf.synthetic_tracer(TRUTH, None)
    effluent.attrs["meta_injected_tds"] = effluent.attrs["meta_initial_tds"]
    with pytest.raises(FitError, match="no tracer step"):
        tf.fit_tracer(effluent, calibration)
