"""Morris elementary effects through spflow's wrapper: exact effects of a linear function, inert inputs ranked last."""

import numpy as np
import pytest
from oracles.sensitivity_benchmarks import ishigami

from spflow.core.errors import ParameterError
from spflow.plugins.screening.morris import morris_indices, morris_sample


def test_linear_function_effects_equal_slope_times_range():
    names = ["a", "b", "c", "d"]
    lower, upper = np.array([0.0, -2.0, 10.0, 5.0]), np.array([1.0, 2.0, 30.0, 5.5])
    slope = np.array([3.0, -1.5, 0.25, 0.0])
    x = morris_sample(names, lower, upper, 10, levels=4, seed=1)
    assert x.shape == (10 * 5, 4) and (x >= lower).all() and (x <= upper).all()
    ds = morris_indices(x, x @ slope + 7.0, names, lower, upper, levels=4, seed=2)
    # an elementary effect is the change over a step Delta of the unit range, divided by Delta: slope * range
    np.testing.assert_allclose(ds["mu"].values[0], slope * (upper - lower), rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(ds["mu_star"].values[0], np.abs(slope) * (upper - lower), rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(ds["sigma"].values[0], 0.0, atol=1e-9)  # linear: every effect is the same


def test_inert_inputs_rank_last_with_zero_mu_star():
    names = ["x1", "x2", "x3", "inert1", "inert2"]
    lower, upper = np.full(5, -np.pi), np.full(5, np.pi)
    x = morris_sample(names, lower, upper, 20, seed=3)
    ds = morris_indices(x, ishigami(x[:, :3]), names, lower, upper, seed=4)
    mu_star = ds["mu_star"].values[0]
    assert mu_star[3] == 0.0 and mu_star[4] == 0.0
    assert (mu_star[:3] > 0.5).all()  # x3 acts through b x3^4 sin x1: visible to Morris although S3 = 0
    assert set(np.argsort(mu_star)[:2]) == {3, 4}
    assert (ds["sigma"].values[0, :3] > 0).all()  # non-linear / interacting inputs spread their effects


def test_bad_morris_inputs_raise():
    with pytest.raises(ParameterError, match="levels"):
        morris_sample(["a"], np.zeros(1), np.ones(1), 4, levels=3)
    with pytest.raises(ParameterError, match="trajectories"):
        morris_sample(["a"], np.zeros(1), np.ones(1), 1)
    x = morris_sample(["a", "b"], np.zeros(2), np.ones(2), 4, seed=0)
    with pytest.raises(ParameterError, match="trajectories of d"):
        morris_indices(x[:-1], x[:-1, 0], ["a", "b"], np.zeros(2), np.ones(2))
