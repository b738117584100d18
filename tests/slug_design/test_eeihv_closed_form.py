"""Closed-form two-objective EEIHV against independent references: a Monte Carlo average of hypervolume
improvements computed with moocore's exact hypervolume, finite differences, and its two limits (docs/eeihv.md §2). The
closed form itself never computes a hypervolume."""

import moocore
import numpy as np
import pytest

from spflow.core.errors import ParameterError
from spflow.plugins.slug_design.eeihv import eeihv, eeihv_and_gradient


def random_front(rng, k):
    """k mutually non-dominated points (minimisation): a random convex-ish decreasing staircase."""
    f1 = np.sort(rng.uniform(0.0, 1.0, k))
    f2 = np.sort(rng.uniform(0.0, 1.0, k))[::-1]
    return np.column_stack([f1, f2 + 0.01 * np.arange(k)[::-1]])  # strictly decreasing f2


def hypervolume_improvement(front, point, reference):
    """HV(front ∪ {point}) − HV(front), both with moocore (independent of the code under test)."""
    union = np.vstack([front, point[None, :]])
    return moocore.hypervolume(union, ref=reference) - moocore.hypervolume(front, ref=reference)


@pytest.mark.parametrize("case", range(5))
def test_closed_form_equals_monte_carlo(case):
    rng = np.random.default_rng(case)
    k = [0, 1, 3, 6, 10][case]
    front = random_front(rng, k)
    reference = np.array([1.2, 1.3])
    mu = rng.uniform(0.0, 1.0, 2)
    s = rng.uniform(0.05, 0.4, 2)
    draws = mu + s * rng.standard_normal((20000, 2))
    hvi = np.array([hypervolume_improvement(front, f, reference) for f in draws])
    mc, se = hvi.mean(), hvi.std(ddof=1) / np.sqrt(hvi.size)
    closed = eeihv(mu[None, :], s[None, :], front, reference)[0]
    assert se > 0
    assert abs(closed - mc) < 3 * se, (closed, mc, se)


def test_gradients_equal_finite_differences():
    rng = np.random.default_rng(11)
    front, reference = random_front(rng, 5), np.array([1.1, 1.1])
    mu = rng.uniform(0.1, 0.9, (6, 2))
    s = rng.uniform(0.05, 0.3, (6, 2))
    _, grad_mu, grad_s = eeihv_and_gradient(mu, s, front, reference)
    h = 1e-6
    for k in range(2):
        step = np.zeros(2)
        step[k] = h
        fd_mu = (eeihv(mu + step, s, front, reference) - eeihv(mu - step, s, front, reference)) / (2 * h)
        fd_s = (eeihv(mu, s + step, front, reference) - eeihv(mu, s - step, front, reference)) / (2 * h)
        np.testing.assert_allclose(grad_mu[:, k], fd_mu, rtol=1e-5, atol=1e-9)
        np.testing.assert_allclose(grad_s[:, k], fd_s, rtol=1e-5, atol=1e-9)


def test_vanishes_far_behind_the_front():
    rng = np.random.default_rng(3)
    front, reference = random_front(rng, 6), np.array([1.1, 1.1])
    behind = front.max(axis=0) + np.array([[0.5, 0.5], [2.0, 0.3], [0.3, 2.0]])  # dominated by every front point
    value = eeihv(behind, np.full_like(behind, 0.05), front, reference)
    assert (value >= 0).all() and value.max() < 1e-12
    # the same means with large uncertainty can still improve the front
    assert eeihv(behind, np.full_like(behind, 1.0), front, reference).min() > 1e-3


def test_deterministic_limit_is_the_hypervolume_improvement_of_the_mean():
    rng = np.random.default_rng(5)
    front, reference = random_front(rng, 7), np.array([1.2, 1.2])
    for mu in rng.uniform(-0.2, 1.1, (8, 2)):
        expected = hypervolume_improvement(front, mu, reference)
        for s, tol in [(1e-4, 1e-3), (1e-7, 1e-6)]:
            value = eeihv(mu[None, :], np.array([[s, s]]), front, reference)[0]
            assert abs(value - expected) < tol, (mu, s, value, expected)
        assert eeihv(mu[None, :], np.zeros((1, 2)), front, reference)[0] == pytest.approx(expected, abs=1e-12)


def test_front_points_beyond_the_reference_are_ignored():
    rng = np.random.default_rng(8)
    front, reference = random_front(rng, 4), np.array([1.1, 1.1])
    outside = np.vstack([front, [[-0.5, 1.5]]])  # non-dominated, but not dominating the reference
    mu, s = rng.uniform(0, 1, (5, 2)), rng.uniform(0.05, 0.2, (5, 2))
    np.testing.assert_allclose(eeihv(mu, s, outside, reference), eeihv(mu, s, front, reference))


def test_bad_inputs_name_the_field():
    front, reference = np.array([[0.2, 0.8], [0.6, 0.3]]), np.array([1.0, 1.0])
    with pytest.raises(ParameterError, match="mu and s"):
        eeihv(np.zeros((2, 3)), np.ones((2, 3)), front, reference)
    with pytest.raises(ParameterError, match="s finite and >= 0"):
        eeihv(np.zeros((1, 2)), -np.ones((1, 2)), front, reference)
    with pytest.raises(ParameterError, match="reference"):
        eeihv(np.zeros((1, 2)), np.ones((1, 2)), front, np.array([1.0, np.nan]))
    with pytest.raises(ParameterError, match="non-dominated"):
        eeihv(np.zeros((1, 2)), np.ones((1, 2)), np.array([[0.2, 0.3], [0.6, 0.5]]), reference)
