"""Residual/input cross-correlation: the lag scan against an explicit-covariance GLS regression, a known lagged
dependence found at its lag with its size, constant channels left out, the null draws reused for a layout scanned
again (results equal to fresh scans), and AR(1) noise flagged at the nominal rate over many seeds (while a test that
ignores the AR(1) model is not)."""

import numpy as np
import pytest
from scipy.stats import binom, norm

from spflow.core.errors import ParameterError
from spflow.plugins.forward.schedule import BCF_SCHEDULES
from spflow.plugins.gap.error_model import BlockErrorModel
from spflow.plugins.forward.schedule import Schedule, Slug
from spflow.plugins.gap.input_correlation import CHANNELS, channel_series, input_correlations, lag_scan, lagged
from spflow.plugins.gap.layout import Block, Layout
from spflow.plugins.gap.observed import Experiment
from spflow.synthetic import NoiseModel

STEP = 0.1
QINJ = 0.25  # the run's injection rate (ml/min) where a slug sets none


#: an in-situ rheology flood: water flood at the run's QINJ, polymer at 0.5 then 1.0 ml/min, chase water at 0.1 ml/min
RATE_STEPS = Schedule((Slug("WF", 0.5, 9400.0), Slug("P1", 1.0, 9400.0, 0.0, 1500.0, 0.5),
                       Slug("P2", 1.0, 9400.0, 0.0, 1500.0, 1.0), Slug("CW", 1.0, 9400.0, rate_ml_min=0.1)), "RATES")


def experiment(schedule="BCF1"):
    s = RATE_STEPS if schedule == "RATES" else BCF_SCHEDULES[schedule]
    pv = np.round(np.arange(1, int(round(s.total_pv / STEP)) + 1) * STEP, 10)
    return Experiment(schedule, s, {}, NoiseModel(), True, pv, STEP, {}, None, None)


def ar1_covariance(scale, phi):
    n = scale.size
    corr = phi ** np.abs(np.subtract.outer(np.arange(n), np.arange(n)))
    return corr * np.outer(scale, scale)


def test_channel_series_follows_the_schedule():
    exp = experiment("BCF2")  # IWF 1.6, HTDS 1.0, SP 0.25, P 0.5, EWF 1.59 PV
    pv = np.array([-0.3, 0.5, 2.0, 2.7, 3.0, 4.0])
    assert list(channel_series(exp, "salinity_ppm", pv, QINJ)) == [9400, 9400, 17500, 17500, 9400, 9400]
    assert list(channel_series(exp, "polymer_ppm", pv, QINJ)) == [0, 0, 0, 2500, 2500, 0]
    assert list(channel_series(exp, "surfactant_ppm", pv, QINJ)) == [0, 0, 0, 6780, 0, 0]
    x = lagged(exp, "polymer_ppm", pv, np.array([0.0, 0.5]), QINJ)
    assert list(x[:, 1]) == list(channel_series(exp, "polymer_ppm", pv - 0.5, QINJ))
    with pytest.raises(ParameterError, match="allowed \\['salinity_ppm'"):
        channel_series(exp, "rate", pv, QINJ)


def test_the_rate_channel_is_each_slugs_rate_or_the_runs_qinj():
    exp = experiment("RATES")
    pv = np.array([0.2, 1.0, 2.0, 3.0])
    assert list(channel_series(exp, "rate_ml_min", pv, QINJ)) == [QINJ, 0.5, 1.0, 0.1]
    assert list(channel_series(experiment("BCF2"), "rate_ml_min", pv, QINJ)) == [QINJ] * 4  # no rate steps


def test_a_residual_that_follows_the_rate_steps_is_credited_to_the_rate():
    # a shear-thinning-like misfit: extra pressure drop in proportion to the rate, at no lag
    exp = experiment("RATES")
    noise = BlockErrorModel(np.full(exp.pv.size, 50.0), 0.6)
    size = 300.0  # Pa over the rate's full range (0.1 .. 1.0 ml/min)
    rate = np.array([{0: QINJ, 1: 0.5, 2: 1.0, 3: 0.1}[k] for k in exp.slug_index(exp.pv)])  # by hand
    e = noise.draw(np.random.default_rng(3), 1)[0] + size * (rate - rate.min()) / np.ptp(rate)
    block = Block("dp", exp.name, np.arange(exp.pv.size), exp.pv, np.zeros(exp.pv.size), exp.slug_index(exp.pv),
                  noise)
    found = input_correlations(Layout((block,)), noise.whiten(e), [exp], {exp.name: QINJ}, 0.01, 1.0, STEP,
                               draws=5000)
    top = found[0]
    assert {c.channel for c in found} == {"polymer_ppm", "rate_ml_min"}  # salinity and surfactant are constant
    assert (top.channel, top.significant, top.lag) == ("rate_ml_min", True, 0.0)
    assert top.channel_range == pytest.approx(0.9)
    assert top.effect == pytest.approx(size, rel=0.2)


@pytest.mark.parametrize("phi", [0.0, 0.6, 1.0])
def test_lag_scan_matches_explicit_gls(phi):
    rng = np.random.default_rng(4)
    n = 35
    scale = rng.uniform(0.5, 2.0, n)
    noise = BlockErrorModel(scale, phi)
    x = np.stack([(np.arange(n) >= 10 + 3 * j) & (np.arange(n) < 22 + 3 * j) for j in range(4)], 1) * 500.0
    e = noise.draw(rng, 1)[0] + 0.004 * x[:, 2] + (0.8 if phi < 1 else 0.0)
    z, beta, p = lag_scan(noise.whiten(e), noise, x, 4000, rng)
    if phi == 1.0:  # random walk with steps scale_t
        cov = np.minimum.outer(np.cumsum(scale**2), np.cumsum(scale**2))
    else:
        cov = ar1_covariance(scale, phi)
    inv = np.linalg.inv(cov)
    for j in range(x.shape[1]):
        design = np.column_stack([np.ones(n), x[:, j]])
        info = np.linalg.inv(design.T @ inv @ design)
        coef = info @ design.T @ inv @ e
        r = e - design @ coef
        s = max(1.0, np.sqrt(r @ inv @ r / (n - 2)))
        assert beta[j] == pytest.approx(coef[1], rel=1e-8)
        assert z[j] == pytest.approx(coef[1] / (s * np.sqrt(info[1, 1])), rel=1e-8)
    assert 0.0 < p <= 1.0


def test_known_lagged_dependence_is_found_at_its_lag():
    exp = experiment("BCF2")
    noise = BlockErrorModel(np.full(exp.pv.size, 60.0), 0.7)
    true_lag, size = 0.4, 400.0  # Pa of extra residual while polymer was injected 0.4 PV earlier
    rng = np.random.default_rng(11)
    e = noise.draw(rng, 1)[0] + size * channel_series(exp, "polymer_ppm", exp.pv - true_lag, QINJ) / 2500.0
    block = Block("dp", exp.name, np.arange(exp.pv.size), exp.pv, np.zeros(exp.pv.size), exp.slug_index(exp.pv),
                  noise)
    found = input_correlations(Layout((block,)), noise.whiten(e), [exp], {exp.name: QINJ}, 0.01, 1.5, STEP,
                               draws=5000)
    assert {c.channel for c in found} == {"salinity_ppm", "surfactant_ppm", "polymer_ppm"}  # all vary in BCF2
    top = found[0]
    assert (top.channel, top.significant) == ("polymer_ppm", True)
    assert top.lag == pytest.approx(true_lag)
    assert top.effect == pytest.approx(size, rel=0.25)
    assert top.lags[-1] == pytest.approx(1.5) and top.lags.size == 16


def test_constant_channels_are_left_out():
    exp = experiment("BCF1")  # 9400 ppm throughout
    noise = BlockErrorModel(np.ones(exp.pv.size), 0.0)
    block = Block("oil_cut", exp.name, np.arange(exp.pv.size), exp.pv, np.zeros(exp.pv.size),
                  exp.slug_index(exp.pv), noise)
    found = input_correlations(Layout((block,)), np.random.default_rng(0).normal(size=exp.pv.size), [exp],
                               {exp.name: QINJ}, 0.01, 1.0, STEP, draws=500)
    assert sorted(c.channel for c in found) == ["polymer_ppm", "surfactant_ppm"]
    assert lag_scan(np.zeros(5), BlockErrorModel(np.ones(5), 0.3), np.full((5, 2), 7.0), 10,
                    np.random.default_rng(0)) is None
    with pytest.raises(ParameterError, match="max_lag"):
        input_correlations(Layout((block,)), np.zeros(exp.pv.size), [exp], {exp.name: QINJ}, 0.01, -1.0, STEP)


def test_rescanning_a_layout_equals_fresh_scans():
    """A diagnosis scans one layout for its base and its final model: the second scan reuses the null draws of the
    first; both equal scan-by-scan lag scans drawing their nulls in order from a fresh generator (module
    docstring), whatever the residuals."""
    exps = [experiment("BCF1"), experiment("BCF2")]
    blocks = []
    for k, exp in enumerate(exps):
        noise = BlockErrorModel(np.full(exp.pv.size, 1.0 + k), 0.5)
        blocks.append(Block("dp", exp.name, np.arange(exp.pv.size), exp.pv, np.zeros(exp.pv.size),
                            exp.slug_index(exp.pv), noise))
    lay = Layout(tuple(blocks))
    lags = np.arange(11) * STEP
    rng = np.random.default_rng(8)
    for reuse in (True, True, False):   # the first call draws the nulls, the second reuses them, the third not
        w = rng.normal(size=lay.size) + 0.5 * np.concatenate(
            [channel_series(e, "polymer_ppm", e.pv - 0.3, QINJ) / 2500.0 for e in exps])
        found = input_correlations(lay, w, exps, {e.name: QINJ for e in exps}, 0.01, 1.0, STEP, draws=3000, seed=5,
                                   reuse=reuse)
        fresh, expected = np.random.default_rng(5), {}
        for b, s, exp in zip(lay.blocks, lay.slices(), exps):
            for channel in CHANNELS:
                scan = lag_scan(w[s], b.noise, lagged(exp, channel, b.pv, lags, QINJ), 3000, fresh)
                if scan is not None:
                    expected[(b.experiment, channel)] = scan
        assert {(c.experiment, c.channel) for c in found} == set(expected)
        for c in found:
            z, beta, p = expected[(c.experiment, c.channel)]
            np.testing.assert_array_equal(c.z, z)
            np.testing.assert_array_equal(c.beta, beta)
            assert c.pvalue == p
        assert len({c.pvalue for c in found}) > 1


def test_ar1_noise_is_flagged_at_the_nominal_rate():
    exp = experiment("BCF2")
    lags = np.arange(16) * STEP
    x = lagged(exp, "polymer_ppm", exp.pv, lags, QINJ)
    noise = BlockErrorModel(np.full(exp.pv.size, 1.0), 0.85)
    rng = np.random.default_rng(2025)
    reps, level = 300, 0.05
    rejected, naive = 0, 0
    for _ in range(reps):
        e = noise.draw(rng, 1)[0]
        rejected += lag_scan(noise.whiten(e), noise, x, 400, rng)[2] < level
        # the same residual tested as if it were white (lag 0): the AR(1) correlation is mistaken for a signal
        xc = x[:, 0] - x[:, 0].mean()
        naive += 2 * norm.sf(abs(xc @ (e - e.mean())) / np.linalg.norm(xc)) < level
    assert binom.cdf(rejected, reps, level) > 0.001 and binom.sf(rejected - 1, reps, level) > 0.001
    assert naive > 4 * reps * level
