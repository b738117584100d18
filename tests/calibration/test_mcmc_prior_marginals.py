"""The MCMC prior from the space's marginals (issue #24): the log prior is the sum of the marginals' log densities.

References computed here:

* one parameter, f(θ) = a θ + b observed with known Gaussian noise: with a normal prior N(m0, s0²) the posterior is
  normal with precision 1/s0² + Σa²/σ² (conjugate); with the prior truncated to [l, u] it is that normal truncated to
  [l, u] (scipy.stats.truncnorm). The "normal" prior is a truncated normal cut 12 prior sd away (a space's marginals
  live on its range), over 12 posterior sd from the posterior mean, which moves no moment by more than 1e-30. Mean and sd within 4-5 Monte Carlo standard errors
  from ArviZ's effective sample size of independent series;
* uniform marginals: the log posterior is the log likelihood minus Σ log(upper − lower) exactly, the starting points
  are ``rng.uniform(lower, upper)`` bit for bit, and both samplers give the same chains, bit for bit, on a space that
  records uniform marginals and on one that records none (the box of Eq. 4.2).
"""

import numpy as np
import pytest
from scipy import stats
from test_mcmc_toys import LinearToy, observations_for, outputs_for, space_for
from test_mcmc_toys import toy_kind_registered  # noqa: F401  (autouse fixture: registers the toy surrogate kind)

from spflow.core.errors import ParameterError
from spflow.core.stage import StageContext
from spflow.plugins.calibration.aligned_data import align
from spflow.plugins.calibration.diagnostics import arviz, independent_series
from spflow.plugins.calibration.emcee_sampler import EmceeSampler, initial_points
from spflow.plugins.calibration.inference_data import to_inference_data
from spflow.plugins.calibration.likelihood import PosteriorModel
from spflow.plugins.calibration.mh_sampler import MHSampler
from spflow.plugins.calibration.parameter_prior import ParameterPrior
from spflow.plugins.calibration.posterior import POSTERIOR
from spflow.plugins.surrogates.input_marginals import Beta, TruncatedNormal, Uniform, marginal_variables

CTX = StageContext("posterior", n_jobs=1, verbose=False)
FAST = {"samples": 24_000, "burn": 4_000, "thin": 2, "chains": 4, "seed": 3}
SAMPLERS = [(EmceeSampler, {"walkers": 8}), (MHSampler, {})]
SIGMA = 0.4


def _one_parameter_problem(n=6, seed=0):
    rng = np.random.default_rng(seed)
    index = outputs_for({("dp", "BCF1"): n})
    a, b = rng.normal(size=(n, 1)), rng.normal(size=n)
    y = a[:, 0] * 0.7 + b + SIGMA * rng.normal(size=n)
    precision = float(a[:, 0] @ a[:, 0]) / SIGMA**2
    theta_hat = float(a[:, 0] @ (y - b)) / float(a[:, 0] @ a[:, 0])
    return index, a, b, y, precision, theta_hat


def _posterior(stage_cls, extra, law, lower, upper, problem):
    index, a, b, y, *_ = problem
    toy = LinearToy(["p"], [lower], [upper], index, a, b, np.zeros(len(index)))
    space = space_for(["p"], [lower], [upper]).assign(marginal_variables([law]))
    posterior = stage_cls(noise="known", sigma=[SIGMA], variables=["dp"], **FAST, **extra).run(
        CTX, surrogate=toy.to_dataset(), observations=observations_for(index, y), space=space)
    POSTERIOR.validate(posterior, stage=stage_cls.name, port="output")
    return posterior


def _assert_mean_and_sd(posterior, mean, sd):
    series = independent_series(posterior)[:, :, 0]
    ess = float(arviz().ess(series, method="mean"))
    draws = posterior["theta"].values.ravel()
    assert ess > 300
    assert abs(draws.mean() - mean) < 4 * sd / np.sqrt(ess)
    assert abs(draws.std() - sd) < 5 * sd / np.sqrt(2 * ess)  # sd of a sample sd of a near-normal law
    return sd / np.sqrt(ess)


@pytest.mark.parametrize("stage_cls, extra", SAMPLERS, ids=["emcee", "mh"])
def test_normal_prior_gives_the_conjugate_normal_posterior(stage_cls, extra):
    problem = _one_parameter_problem()
    *_, precision, theta_hat = problem
    m0, s0 = -0.5, 0.15  # an informative prior: ignoring it moves the mean by over 20 Monte Carlo errors
    post_precision = 1 / s0**2 + precision
    mean, sd = (m0 / s0**2 + theta_hat * precision) / post_precision, post_precision**-0.5
    lower, upper = m0 - 12 * s0, m0 + 12 * s0
    posterior = _posterior(stage_cls, extra, TruncatedNormal(m0, s0, lower, upper), lower, upper, problem)
    error = _assert_mean_and_sd(posterior, mean, sd)
    assert abs(theta_hat - mean) > 20 * error  # the flat-prior answer is far off
    assert posterior.attrs["prior"] == f"p ~ TruncatedNormal(mean=-0.5, std=0.15, lower={lower:g}, upper={upper:g})"
    assert posterior.attrs["prior_note"] == ""
    assert posterior["distribution"].values.tolist() == ["truncated_normal"]


@pytest.mark.parametrize("stage_cls, extra", SAMPLERS, ids=["emcee", "mh"])
def test_truncated_normal_prior_gives_the_truncated_normal_posterior(stage_cls, extra):
    problem = _one_parameter_problem(seed=1)
    *_, precision, theta_hat = problem
    m0, s0, lower, upper = 0.0, 0.2, -0.1, 0.4  # truncation cuts into the posterior on both sides
    post_precision = 1 / s0**2 + precision
    loc, scale = (m0 / s0**2 + theta_hat * precision) / post_precision, post_precision**-0.5
    reference = stats.truncnorm((lower - loc) / scale, (upper - loc) / scale, loc=loc, scale=scale)
    assert reference.std() < 0.8 * scale  # the truncation matters
    posterior = _posterior(stage_cls, extra, TruncatedNormal(m0, s0, lower, upper), lower, upper, problem)
    error = _assert_mean_and_sd(posterior, reference.mean(), reference.std())
    draws = posterior["theta"].values.ravel()
    assert draws.min() >= lower and draws.max() <= upper
    # a uniform prior on the same box gives the likelihood truncated to it: another law
    flat = stats.truncnorm((lower - theta_hat) * np.sqrt(precision), (upper - theta_hat) * np.sqrt(precision),
                           loc=theta_hat, scale=precision**-0.5)
    assert abs(flat.mean() - reference.mean()) > 10 * error


def test_uniform_marginals_give_the_box_chains_bit_for_bit():
    problem = _one_parameter_problem(n=8, seed=2)
    index, a, b, y, *_ = problem
    a2 = np.column_stack([a[:, 0], np.random.default_rng(9).normal(size=len(index))])
    toy = LinearToy(["p", "q"], [-3, -2], [3, 4], index, a2, b, np.full(len(index), 0.01))
    box = space_for(["p", "q"], [-3, -2], [3, 4])
    recorded = box.assign(marginal_variables([Uniform(-3, 3), Uniform(-2, 4)]))
    small = {"samples": 2_000, "burn": 400, "thin": 2, "chains": 2, "seed": 5, "variables": ["dp"]}
    for stage in (EmceeSampler(walkers=6, init="best", init_draws=64, **small), MHSampler(**small)):
        runs = [stage.run(CTX, surrogate=toy.to_dataset(), observations=observations_for(index, y), space=space)
                for space in (box, recorded)]
        for key in ("theta", "sigma", "log_posterior", "log_likelihood", "acceptance"):
            np.testing.assert_array_equal(runs[0][key].values, runs[1][key].values)
        assert runs[0].attrs["prior"] == runs[1].attrs["prior"] == "p ~ Uniform(lower=-3, upper=3)\n" \
                                                                  "q ~ Uniform(lower=-2, upper=4)"
        assert "uniform on its range" in runs[0].attrs["prior_note"] and runs[1].attrs["prior_note"] == ""


def test_uniform_prior_is_the_box_of_eq_4_2_to_the_last_bit():
    problem = _one_parameter_problem(n=8, seed=2)
    index, a, b, y, *_ = problem
    lower, upper = np.array([-3.0, -2.0]), np.array([3.0, 4.0])
    a2 = np.column_stack([a[:, 0], a[::-1, 0]])
    toy = LinearToy(["p", "q"], lower, upper, index, a2, b, np.zeros(len(index)))
    pairs = [("dp", "BCF1")]
    model = PosteriorModel(toy, align(toy.outputs, observations_for(index, y), pairs), pairs, lower, upper,
                           noise="known", sigma=(SIGMA,))
    rng = np.random.default_rng(0)
    x = rng.uniform(lower - 1, upper + 1, (200, 2))
    log_post, log_lik = model.evaluate(x)
    inside = np.all((x >= lower) & (x <= upper), axis=1)
    np.testing.assert_array_equal(log_post[inside], log_lik[inside] - np.sum(np.log(upper - lower)))
    assert np.isneginf(log_post[~inside]).all() and (~inside).sum() > 20
    # the starting points: the box draw rng.uniform(lower, upper) from the same generator state
    for how in ("prior", "best"):
        start = initial_points(model, 7, how, 50, np.random.default_rng(4))
        pool = np.random.default_rng(4).uniform(lower, upper, size=(7 if how == "prior" else 50, 2))
        expected = pool if how == "prior" else pool[np.argsort(-model.evaluate(pool)[0])[:7]]
        np.testing.assert_array_equal(start, expected)


def test_walkers_start_inside_the_support_drawn_from_the_prior_and_leaving_it_is_impossible():
    laws = [TruncatedNormal(0.2, 0.3, 0.0, 0.35), Beta(3.0, 2.0, -1.0, 2.0)]
    index = outputs_for({("dp", "BCF1"): 3})
    toy = LinearToy(["p", "q"], [0.0, -1.0], [0.35, 2.0], index, np.ones((3, 2)), np.zeros(3), np.zeros(3))
    pairs = [("dp", "BCF1")]
    model = PosteriorModel(toy, align(toy.outputs, observations_for(index, np.zeros(3)), pairs), pairs,
                           [0.0, -1.0], [0.35, 2.0], noise="known", sigma=(1.0,), prior=ParameterPrior(["p", "q"], laws))
    start = initial_points(model, 4000, "prior", 0, np.random.default_rng(1))
    assert stats.kstest(start[:, 0], stats.truncnorm(-2 / 3, 0.5, loc=0.2, scale=0.3).cdf).pvalue > 1e-3
    assert stats.kstest(start[:, 1], stats.beta(3.0, 2.0, loc=-1.0, scale=3.0).cdf).pvalue > 1e-3
    # the log prior: the sum of scipy's log densities; -inf outside the supports and where the density is 0
    theta = np.array([[0.1, 0.5], [0.3, 1.9], [0.36, 0.0], [0.1, -1.0], [-0.01, 0.0]])
    log_post, log_lik = model.evaluate(theta)
    expected = (stats.truncnorm(-2 / 3, 0.5, loc=0.2, scale=0.3).logpdf(theta[:2, 0])
                + stats.beta(3.0, 2.0, loc=-1.0, scale=3.0).logpdf(theta[:2, 1]))
    np.testing.assert_allclose(log_post[:2] - log_lik[:2], expected, rtol=1e-12)
    assert np.isneginf(log_post[2:]).all()


def test_prior_is_printed_and_carried_into_the_inference_data_and_the_figure(capsys, tmp_path):
    problem = _one_parameter_problem(n=5, seed=4)
    index, a, b, y, *_ = problem
    law = TruncatedNormal(0.5, 0.5, 0.0, 2.0)
    toy = LinearToy(["p"], [0.0], [2.0], index, a, b, np.zeros(len(index)))
    space = space_for(["p"], [0.0], [2.0]).assign(marginal_variables([law]))
    obs = observations_for(index, y)
    posterior = EmceeSampler(samples=400, burn=100, thin=1, chains=1, walkers=4, noise="known", sigma=[SIGMA],
                             variables=["dp"]).run(StageContext("posterior", verbose=True),
                                                   surrogate=toy.to_dataset(), observations=obs, space=space)
    assert "[posterior] prior:\n  p ~ TruncatedNormal(mean=0.5, std=0.5, lower=0, upper=2)" in capsys.readouterr().err
    data = to_inference_data(posterior, toy.to_dataset(), obs, prior_draws=3000)
    draws = data.prior["p"].values.ravel()
    assert stats.kstest(draws, stats.truncnorm(-1, 3, loc=0.5, scale=0.5).cdf).pvalue > 1e-3
    assert data.constant_data["distribution"].values.tolist() == ["truncated_normal"]
    from spflow.plugins.calibration.mcmc_figures import prior_posterior_figure

    assert prior_posterior_figure(posterior, tmp_path / "prior.png").stat().st_size > 0


def test_a_marginal_off_the_box_or_unbounded_is_refused():
    index = outputs_for({("dp", "BCF1"): 3})
    toy = LinearToy(["p"], [0.0], [1.0], index, np.ones((3, 1)), np.zeros(3), np.zeros(3))
    space = space_for(["p"], [0.0], [1.0]).assign(marginal_variables([Beta(2.0, 2.0, 0.0, 2.0)]))
    with pytest.raises(ParameterError, match="stage 'mh_sampler': parameter 'p' of the space has the distribution"):
        MHSampler(samples=100, burn=10, noise="known", sigma=[1.0], variables=["dp"]).run(
            CTX, surrogate=toy.to_dataset(), observations=observations_for(index, np.zeros(3)), space=space)
    from spflow.plugins.surrogates.input_marginals import Normal

    with pytest.raises(ParameterError, match="unbounded support"):
        ParameterPrior(["p"], [Normal(0.0, 1.0)])
