"""Tracer / conductivity fit (Fig. 2.9): Ogata-Banks vs the test oracle and the hand values of docs/forward_model.md,
recovery, coverage, errors."""

import numpy as np
import pytest
from scipy import stats
from scipy.optimize import minimize_scalar
from scipy.stats import binom

from oracles import ogata_banks
from spflow.core.stage import StageContext
from spflow.plugins.lab import tracer_fit as tf
from spflow.plugins.lab.fit_result import FIT, FitError, stated_interval
from spflow.plugins.lab.polymer_fit_figures import tracer_figure
from spflow.plugins.lab.polymer_fit_stages import FitTracer

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


def test_truth_inside_stated_95_percent_interval_over_seeds():
    # 40 regenerated data sets; the stated interval is the profile-likelihood one. With a correct 95 % interval the
    # count inside is < 35 with probability 0.014 (binomial, computed below); an 80 % interval passes with 0.16.
    # The spread check (scatter of the estimates / mean std) fails intervals too wide or too narrow by ~1.5x.
    n = 40
    need = 35
    assert binom.cdf(need - 1, n, 0.95) < 0.015 and binom.sf(need - 1, n, 0.80) < 0.17
    hits = dict.fromkeys(tf.NAMES, 0)
    est, std = [], []
    for seed in range(n):
        fit = tf.fit_tracer(*tf.synthetic_tracer(TRUTH, np.random.default_rng(4000 + seed)))
        assert fit.attrs["stated_interval"] == "profile"
        lo, hi = stated_interval(fit)
        for name in tf.NAMES:
            hits[name] += bool(lo.sel(param=name) <= TRUTH[name] <= hi.sel(param=name))
        est.append(fit["estimate"].values)
        std.append(fit["std"].values)
    assert all(h >= need for h in hits.values()), hits
    spread = np.std(est, axis=0, ddof=1) / np.mean(std, axis=0)
    assert np.all((0.65 < spread) & (spread < 1.5)), spread


def test_profile_ends_match_brute_force_profile_of_the_dispersivity():
    # at each end of ALPHAL1's profile interval the RSS minimised over TDS_PER_EC (minimize_scalar, not
    # least_squares) equals the F threshold RSS_min (1 + t^2/dof)
    effluent, calibration = tf.synthetic_tracer(TRUTH, np.random.default_rng(7))
    fit = tf.fit_tracer(effluent, calibration)
    pv, ec = effluent["pv"].values, effluent["conductivity"].values
    tds, ec_cal = calibration["tds"].values, calibration["conductivity"].values
    scale = np.mean(np.abs(ec))

    def profiled(alpha):
        def rss(a):
            r = np.concatenate([tf.effluent_conductivity(pv, alpha, a, 0.1524, 9400.0, 17500.0) - ec, tds / a - ec_cal])
            return np.sum((r / scale) ** 2)
        return minimize_scalar(rss, bounds=(550.0, 650.0), method="bounded", options={"xatol": 1e-9}).fun

    dof = fit.attrs["dof"]
    threshold = fit.attrs["rss"] * (1 + stats.t.ppf(0.975, dof) ** 2 / dof)
    for end in ("profile_lower", "profile_upper"):
        alpha = float(fit[end].sel(param="ALPHAL1"))
        assert profiled(alpha) == pytest.approx(threshold, rel=1e-6), end
    lo, hi = fit["profile_lower"].sel(param="ALPHAL1"), fit["profile_upper"].sel(param="ALPHAL1")
    assert profiled(float(0.5 * (lo + hi))) < threshold


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
