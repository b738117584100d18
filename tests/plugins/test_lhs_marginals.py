"""The ``lhs_design`` stage under the space's marginals (issue #24), and the chapter-4 prior design that uses it.

References computed here: the Latin hypercube on [0, 1]^d from ``scipy.stats.qmc.LatinHypercube`` with the stage's
seed, scaled by hand (lower + (upper − lower) u) or mapped through ``scipy.stats`` quantile functions built in the
test; the strata of each column on its marginal's cdf (``scipy.stats`` cdf of the drawn values); the means and
variances of the truncated normal and beta laws written out by hand (Johnson, Kotz & Balakrishnan).
"""

import numpy as np
import pytest
import xarray as xr
from scipy import special, stats
from scipy.stats import qmc

import spflow
from spflow.core.cf_metadata import UNITS_VARIABLE
from spflow.core.errors import ParameterError
from spflow.core.stage import StageContext
from spflow.pipelines import bayesian_calibration
from spflow.plugins.design.latin_hypercube import LatinHypercubeDesign
from spflow.plugins.surrogates.input_marginals import (Beta, TruncatedNormal, Uniform, marginal_variables,
                                                       marginals_from_dataset)

CTX = StageContext("design", verbose=False)
NAMES = ["HBNC70", "E2C", "AD31"]
LOWER, UPPER = np.array([0.02, 1.5, 0.0]), np.array([0.05, 3.0, 2.0])
#: HBNC70: a lab fit's N(0.03, 0.005²) cut to its box; E2C: Beta(2, 5) on its range; AD31 stays uniform
LAWS = [TruncatedNormal(0.03, 0.005, 0.02, 0.05), Beta(2.0, 5.0, 1.5, 3.0), Uniform(0.0, 2.0)]
#: the same laws from scipy.stats directly (the test's own quantile and cdf functions)
SCIPY = [stats.truncnorm((0.02 - 0.03) / 0.005, (0.05 - 0.03) / 0.005, loc=0.03, scale=0.005),
         stats.beta(2.0, 5.0, loc=1.5, scale=1.5), stats.uniform(0.0, 2.0)]


def _space(laws=None):
    per = {UNITS_VARIABLE: "unit"}
    space = xr.Dataset({"lower": ("param", LOWER, per), "upper": ("param", UPPER, per),
                        "default": ("param", [0.03, 2.0, 1.0], per), "unit": ("param", ["1", "1", "1"])},
                       coords={"param": NAMES})
    return space if laws is None else space.assign(marginal_variables(laws))


def _truncnorm_moments(mean, std, lower, upper):
    """Mean and variance of N(mean, std²) truncated to [lower, upper] (Johnson, Kotz & Balakrishnan, Eq. 13.134)."""
    a, b = (lower - mean) / std, (upper - mean) / std
    z = special.ndtr(b) - special.ndtr(a)
    pa, pb = np.exp(-0.5 * a * a) / np.sqrt(2 * np.pi), np.exp(-0.5 * b * b) / np.sqrt(2 * np.pi)
    return mean + std * (pa - pb) / z, std**2 * (1 + (a * pa - b * pb) / z - ((pa - pb) / z) ** 2)


def _beta_moments(alpha, beta, lower, upper):
    """Mean and variance of Beta(alpha, beta) stretched onto [lower, upper]."""
    width = upper - lower
    return (lower + width * alpha / (alpha + beta),
            width**2 * alpha * beta / ((alpha + beta) ** 2 * (alpha + beta + 1)))


@pytest.mark.parametrize("seed, optimization", [(0, "none"), (11, "random-cd")])
def test_no_marginals_and_uniform_marginals_give_the_box_design_bit_for_bit(seed, optimization):
    opt = None if optimization == "none" else optimization
    unit = qmc.LatinHypercube(d=3, rng=seed, optimization=opt).random(50)
    by_hand = LOWER + unit * (UPPER - LOWER)
    stage = LatinHypercubeDesign(samples=50, seed=seed, optimization=optimization)
    box = stage.run(CTX, _space())
    uniform = stage.run(CTX, _space([Uniform(lo, hi) for lo, hi in zip(LOWER, UPPER)]))
    np.testing.assert_array_equal(box["values"].values, by_hand)
    np.testing.assert_array_equal(uniform["values"].values, by_hand)
    assert box.attrs["marginals"] == "uniform on the ranges (the space records no marginals)"
    assert "distribution" not in box
    assert uniform.attrs["marginals"].splitlines()[0] == "HBNC70 ~ Uniform(lower=0.02, upper=0.05)"


def test_each_column_has_one_point_per_stratum_of_its_marginals_cdf():
    n = 64
    design = LatinHypercubeDesign(samples=n, seed=5).run(CTX, _space(LAWS))
    x = design["values"].values
    for j, law in enumerate(SCIPY):
        strata = np.floor(law.cdf(x[:, j]) * n).astype(int)
        assert sorted(strata.tolist()) == list(range(n)), NAMES[j]
        assert np.all((x[:, j] >= LOWER[j]) & (x[:, j] <= UPPER[j]))
    # the values are scipy's quantiles of the stage's hypercube (same seed)
    unit = qmc.LatinHypercube(d=3, rng=5).random(n)
    reference = np.column_stack([law.ppf(unit[:, j]) for j, law in enumerate(SCIPY)])
    np.testing.assert_allclose(x, reference, rtol=1e-12, atol=0)
    # not the box's design: on the box, HBNC70 would be uniform on [0.02, 0.05] (a third of its strata in 0.04-0.05)
    assert np.mean(x[:, 0] > 0.04) < 0.05


def test_sample_moments_are_the_marginals_within_monte_carlo_error():
    """n = 4000: each column's mean and variance within 4 standard errors of an independent sample (σ/√n for the mean,
    √((μ4 − σ⁴)/n) for the variance, μ4 from scipy's kurtosis); a Latin hypercube of a monotone function has at most
    that variance (McKay, Beckman & Conover 1979), so the bound is conservative."""
    n = 4000
    x = LatinHypercubeDesign(samples=n, seed=9).run(CTX, _space(LAWS))["values"].values
    exact = [_truncnorm_moments(0.03, 0.005, 0.02, 0.05), _beta_moments(2.0, 5.0, 1.5, 3.0), (1.0, 4.0 / 12)]
    for j, ((mean, var), law) in enumerate(zip(exact, SCIPY)):
        mu4 = (float(law.stats(moments="k")) + 3.0) * var**2
        assert abs(x[:, j].mean() - mean) < 4 * np.sqrt(var / n), NAMES[j]
        assert abs(x[:, j].var(ddof=1) - var) < 4 * np.sqrt((mu4 - var**2) / n), NAMES[j]
    # the beta's mean is 1.5 + 1.5 * 2/7 = 1.93, not the range's middle 2.25 (so the test sees the marginal)
    assert abs(x[:, 1].mean() - 2.25) > 0.3


def test_the_laws_are_printed_and_recorded(capsys):
    design = LatinHypercubeDesign(samples=8, seed=1).run(StageContext("lhs", verbose=True), _space(LAWS))
    lines = design.attrs["marginals"].splitlines()
    assert lines == ["HBNC70 ~ TruncatedNormal(mean=0.03, std=0.005, lower=0.02, upper=0.05)",
                     "E2C ~ Beta(alpha=2, beta=5, lower=1.5, upper=3)", "AD31 ~ Uniform(lower=0, upper=2)"]
    assert marginals_from_dataset(design, "design") == LAWS  # the variables round-trip
    err = capsys.readouterr().err
    assert "[lhs] Latin hypercube under:" in err and "  E2C ~ Beta(alpha=2, beta=5, lower=1.5, upper=3)" in err
    LatinHypercubeDesign(samples=8, seed=1).run(StageContext("lhs", verbose=True), _space())
    assert "the space records no marginals: uniform on its ranges" in capsys.readouterr().err


def test_a_law_off_the_range_is_refused_before_drawing():
    cut = [TruncatedNormal(0.03, 0.005, 0.025, 0.05), LAWS[1], LAWS[2]]  # cut inside HBNC70's range
    with pytest.raises(ParameterError, match="stage 'lhs_design': parameter 'HBNC70'.*not the space's range"):
        LatinHypercubeDesign(samples=8).run(CTX, _space(cut))


def test_the_chapter_4_prior_design_follows_the_spaces_marginals(tmp_path):
    """``bayesian_calibration``'s ``prior_design`` (which ``prior_responses`` and the prior bands of Fig. 4.5 run)
    is drawn from the marginals of the space it is given (here in place of its own, as ``lab_priors`` does)."""
    p = spflow.Pipeline("prior_band").add_data("space", _space(LAWS))
    p.include(bayesian_calibration.pipeline(quick=True, seed=2024), "bc", share=["space"])
    assert p.nodes["bc.prior_responses"].inputs == {"design": "bc.prior_design"}
    design = spflow.run(p, cache=tmp_path, until="bc.prior_design")["bc.prior_design"]
    n = design.sizes["sample"]
    assert n == 16 and design.attrs["seed"] == 2025
    unit = qmc.LatinHypercube(d=3, rng=2025).random(n)
    np.testing.assert_allclose(design["values"].values,
                               np.column_stack([law.ppf(unit[:, j]) for j, law in enumerate(SCIPY)]), rtol=1e-12)
    for j, law in enumerate(SCIPY):
        assert sorted(np.floor(law.cdf(design["values"].values[:, j]) * n).astype(int).tolist()) == list(range(n))
    assert marginals_from_dataset(design, "prior design") == LAWS
