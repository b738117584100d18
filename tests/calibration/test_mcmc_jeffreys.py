"""The per-QoI noise σ integrated out under Jeffreys' prior: closed form and quadrature against scipy.integrate.quad,
and the conditional draws of σ against their exact distributions."""

from math import gamma, log, pi

import numpy as np
import pytest
from scipy import integrate, stats

from spflow.plugins.calibration import jeffreys


def _quad_log_marginal(r, v):
    """log ∫ Π_k N(r_k | 0, σ² + v_k) p(σ) dσ with p(σ) = σ sqrt(mean_k (σ² + v_k)^-2) (= 1/σ when v = 0), by quad
    over s = log σ, the integrand scaled by its maximum."""
    r, v = np.asarray(r, float), np.broadcast_to(np.asarray(v, float), np.shape(r))

    def log_f(s):
        var = np.exp(2 * s) + v
        prior_times_jacobian = 2 * s + 0.5 * np.log(np.mean(var ** -2.0))  # p(σ) dσ/ds = σ p(σ)
        return -0.5 * np.sum(np.log(2 * pi * var) + r * r / var) + prior_times_jacobian

    grid = np.linspace(-60, 30, 1801)
    top = grid[np.argmax([log_f(s) for s in grid])]
    peak = log_f(top)
    value, _ = integrate.quad(lambda s: np.exp(log_f(s) - peak), top - 40, top + 60, points=[top], epsabs=0,
                              epsrel=1e-13, limit=500)
    return np.log(value) + peak


@pytest.mark.parametrize("n, sum_sq", [(5, 2.3), (40, 17.0), (101, 0.8), (500, 3.0), (1, 0.04), (43, 2.5e9)])
def test_closed_form_equals_quadrature_over_sigma_to_1e_10(n, sum_sq):
    r = np.random.default_rng(n).normal(size=n)
    r *= np.sqrt(sum_sq / np.sum(r * r))
    code = jeffreys.log_marginal(r[None, :], 0.0)[0]
    reference = _quad_log_marginal(r, 0.0)
    assert abs(np.expm1(code - reference)) < 1e-10  # relative error of the likelihood itself


def test_closed_form_is_the_uq_notes_formula():
    n, s = 40, 17.0
    expected = log(0.5 * gamma(n / 2)) - n / 2 * log(pi) - n / 2 * log(s)
    assert jeffreys.log_marginal_closed_form(np.array([s]), n)[0] == pytest.approx(expected, rel=1e-13)


@pytest.mark.parametrize("case", range(12))
def test_quadrature_with_surrogate_variance_matches_quad(case):
    rng = np.random.default_rng(100 + case)
    n = [5, 20, 43, 200][case % 4]
    scale = 10 ** rng.uniform(-3, 5)
    r = rng.normal(size=n) * scale
    v = (scale * 10 ** rng.uniform(-3, 1, size=n)) ** 2 * (rng.random(n) < 0.8)  # some points without error
    code = jeffreys.log_marginal(r[None, :], v[None, :])[0]
    assert code == pytest.approx(_quad_log_marginal(r, v), abs=1e-5)


def test_quadrature_tends_to_the_closed_form_as_the_variance_vanishes():
    r = np.random.default_rng(3).normal(size=(4, 30)) * [[1.0], [10.0], [1e-3], [1e4]]
    v = 1e-14 * np.mean(r * r, axis=1, keepdims=True) * np.ones_like(r)
    np.testing.assert_allclose(jeffreys.log_marginal(r, v), jeffreys.log_marginal(r, 0.0), atol=1e-6)


def test_rows_are_independent():
    rng = np.random.default_rng(4)
    r, v = rng.normal(size=(5, 12)), rng.uniform(0, 0.5, size=(5, 12))
    v[2] = 0.0
    together = jeffreys.log_marginal(r, v)
    alone = [jeffreys.log_marginal(r[i:i + 1], v[i:i + 1])[0] for i in range(5)]
    np.testing.assert_allclose(together, alone, rtol=0, atol=0)


def test_negative_variance_is_rejected():
    with pytest.raises(ValueError, match=">= 0"):
        jeffreys.log_marginal(np.ones((1, 3)), -np.ones((1, 3)))


def test_sigma_draws_without_surrogate_error_are_inverse_gamma():
    n, s = 25, 7.5
    r = np.random.default_rng(5).normal(size=n)
    r *= np.sqrt(s / np.sum(r * r))
    sigma = jeffreys.sample_sigma(np.tile(r, (20000, 1)), 0.0, np.random.default_rng(6))
    ks = stats.kstest(sigma ** 2, stats.invgamma(n / 2, scale=s / 2).cdf)
    assert ks.pvalue > 0.01


def test_sigma_draws_with_surrogate_error_follow_the_conditional_posterior():
    rng = np.random.default_rng(7)
    n = 30
    r = rng.normal(size=n) * 2.0
    v = rng.uniform(0.5, 3.0, size=n)
    draws = jeffreys.sample_sigma(np.tile(r, (4000, 1)), np.tile(v, (4000, 1)), rng)

    def density(sigma):  # unnormalised p(σ | r) with the Jeffreys-rule prior, written out independently
        var = sigma ** 2 + v
        return np.exp(np.sum(stats.norm.logpdf(r, scale=np.sqrt(var))) + 0.5 * np.log(np.mean(var ** -2.0))
                      + np.log(sigma) + 60)

    total = integrate.quad(density, 0, 50, limit=200)[0]
    grid = np.quantile(draws, np.linspace(0.02, 0.98, 25))
    cdf = np.array([integrate.quad(density, 0, g, limit=200)[0] / total for g in grid])
    empirical = np.array([np.mean(draws <= g) for g in grid])
    assert np.max(np.abs(cdf - empirical)) < 0.03  # ~ 2x the KS 5 % critical value for 4000 draws


def test_log_sigma_prior_is_flat_without_surrogate_error_and_finite_at_zero_with_it():
    sigma = np.array([1e-6, 1e-3, 1.0, 1e3])
    np.testing.assert_allclose(jeffreys.log_sigma_prior(sigma, np.zeros((4, 7))), 0.0, atol=1e-12)
    with_error = jeffreys.log_sigma_prior(sigma, np.ones((4, 7)))
    # the density in log σ vanishes like σ² as σ -> 0 (proper) and tends to the flat prior as σ -> infinity
    assert with_error[0] < -25 and with_error[3] == pytest.approx(0.0, abs=1e-5)
