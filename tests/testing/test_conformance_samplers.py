"""``check_sampler`` over both built-in samplers on the 2-D Gaussian target (analytic posterior mean and covariance),
and toy samplers that each break one part of the contract failing the check named for it."""

from __future__ import annotations

import numpy as np
import pytest

from spflow.plugins.calibration.mcmc_stage import ChainResult, SamplerStage
from spflow.plugins.calibration.mh_sampler import MHSampler
from spflow.testing import SAMPLER_CHECKS, ConformanceError, check_sampler
from spflow.testing.gaussian_target import gaussian_target

#: Evaluations per chain: 2 chains of 3000 give ~500 effective draws of each parameter for both samplers.
BUDGETS = {
    "emcee_sampler": {"samples": 3000, "burn": 500, "thin": 1, "chains": 2},
    "mh_sampler": {"samples": 3000, "burn": 750, "thin": 1, "chains": 2, "tune_interval": 250},
}


def test_the_target_moments_are_the_least_squares_solution():
    target = gaussian_target()
    t = np.linspace(0.2, 1.6, 8)
    a = np.column_stack([np.ones_like(t), t])
    d = target.observations["dp"].values[0] - 1.0
    np.testing.assert_allclose(target.mean, np.polyfit(t, d, 1)[::-1], rtol=1e-12)  # numpy's own least squares
    sigma = 0.1
    np.testing.assert_allclose(target.cov, sigma**2 * np.linalg.inv(a.T @ a), rtol=1e-12)
    assert target.cov[0, 1] / np.sqrt(target.cov[0, 0] * target.cov[1, 1]) < -0.85  # strongly correlated (-0.89)


@pytest.mark.parametrize("name", sorted(BUDGETS))
def test_builtin_sampler_conforms(name):
    assert check_sampler(name, BUDGETS[name]).passed == list(SAMPLER_CHECKS)


class PriorOnly(SamplerStage):
    """Ignores the likelihood: independent uniform draws in the box."""

    name = "toy_prior_only"
    params = SamplerStage.common_params

    def _sample_runs(self, ctx, model, seeds):
        out = []
        for seed in seeds:
            x = np.random.default_rng(seed).uniform(model.lower, model.upper, (1, 1000, model.ndim))
            log_post, log_lik = model.evaluate(x[0])
            out.append(ChainResult(x=x, log_posterior=log_post[None], log_likelihood=log_lik[None],
                                   acceptance=np.ones(1)))
        return out


def test_a_sampler_ignoring_the_likelihood_fails_gaussian_moments():
    with pytest.raises(ConformanceError, match="variance of parameter 1") as caught:
        check_sampler(PriorOnly, {"samples": 1000, "burn": 0, "chains": 2})
    assert caught.value.failed == ["gaussian_moments"]


class SeedIgnored(MHSampler):
    name = "toy_seed_ignored"

    def _sample_runs(self, ctx, model, seeds):
        return super()._sample_runs(ctx, model, np.random.SeedSequence(7).spawn(len(seeds)))


def test_a_sampler_ignoring_its_seed_fails_seed_determinism():
    with pytest.raises(ConformanceError, match="the seed is not used") as caught:
        check_sampler(SeedIgnored, BUDGETS["mh_sampler"])
    assert caught.value.failed == ["seed_determinism"]


class Jittered(MHSampler):
    """Adds noise of 0.3 posterior standard deviations to every draw after sampling."""

    name = "toy_jittered"

    def _sample_runs(self, ctx, model, seeds):
        results = super()._sample_runs(ctx, model, seeds)
        sd = np.sqrt(np.diag(gaussian_target().cov))
        for k, r in enumerate(results):
            r["x"] = r["x"] + np.random.default_rng(k).normal(0.0, 0.3 * sd, r["x"].shape)
        return results


def test_draws_pushed_out_of_the_box_fail_prior_support():
    with pytest.raises(ConformanceError, match="outside a box cutting the posterior") as caught:
        check_sampler(Jittered, BUDGETS["mh_sampler"])
    assert "prior_support" in caught.value.failed
