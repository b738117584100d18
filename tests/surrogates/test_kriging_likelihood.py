"""Maximum likelihood of the correlation lengths (Eq. 3.21) through GPy's L-BFGS-B multi-start: the optimum is at
least as good as the best point of a brute-force grid over the length scales, and lies where the grid's best is."""

import numpy as np

from spflow.plugins.surrogates.basis import design_matrix, multi_indices
from spflow.plugins.surrogates.kriging import UniversalKriging
from spflow.plugins.surrogates.kriging_likelihood import LENGTHSCALE_BOUNDS, fit_lengthscales, informative_columns

NUGGET = 1e-8


def _loglik(z, y, basis, trend, ell):
    """Eq. 3.21's log-likelihood at length scales ``ell``."""
    return UniversalKriging(z, y, basis, trend, "gaussian", np.atleast_1d(ell), NUGGET).log_likelihood()


def test_ml_lengthscale_matches_a_grid_search_in_one_dimension():
    z = np.linspace(-1, 1, 15)[:, None]
    y = (np.sin(4 * z[:, 0]) + 0.3 * z[:, 0] ** 2)[:, None]
    basis = design_matrix(z, multi_indices(1, 1))
    trend = np.ones((1, 2), bool)
    grid = np.exp(np.linspace(np.log(0.05), np.log(5.0), 200))
    values = np.array([_loglik(z, y, basis, trend, g) for g in grid])
    best = grid[np.argmax(values)]
    assert LENGTHSCALE_BOUNDS[0] < best < 5.0  # an interior optimum
    ell = fit_lengthscales(z, y, basis, trend, "gaussian", NUGGET, restarts=3, seed=0)
    assert _loglik(z, y, basis, trend, ell) >= values.max() - 1e-6
    assert abs(np.log(ell[0] / best)) < 2 * np.log(grid[1] / grid[0])  # same optimum, to grid resolution


def test_ml_lengthscales_beat_a_grid_in_two_dimensions_with_shared_columns():
    rng = np.random.default_rng(7)
    z = rng.uniform(-1, 1, (20, 2))
    y = np.c_[np.sin(3 * z[:, 0]) * np.cos(z[:, 1]), np.sin(3 * z[:, 0] + 0.5 * z[:, 1])]
    basis = design_matrix(z, multi_indices(2, 1))
    trend = np.array([[1, 1, 0], [1, 0, 1]], dtype=bool)  # different trends, one shared correlation
    axis = np.exp(np.linspace(np.log(0.1), np.log(10.0), 20))
    values = np.array([[_loglik(z, y, basis, trend, [a, b]) for b in axis] for a in axis])
    ell = fit_lengthscales(z, y, basis, trend, "gaussian", NUGGET, restarts=4, seed=1)
    assert _loglik(z, y, basis, trend, ell) >= values.max() - 1e-6


def test_columns_without_information_about_the_lengths_are_left_out():
    rng = np.random.default_rng(3)
    z = rng.uniform(-1, 1, (15, 2))
    signal = np.sin(3 * z[:, 0]) + z[:, 1] ** 2
    constant = np.full(15, 0.125)  # e.g. recovery before breakthrough ...
    roundoff = 0.25 + 1e-12 * rng.normal(size=15)  # ... with round-off noise
    linear = 1.0 + 2.0 * z[:, 1]  # reproduced exactly by its trend (multi-index (0, 1))
    basis = design_matrix(z, multi_indices(2, 1))
    trend = np.array([[1, 0, 0], [1, 0, 0], [1, 0, 0], [1, 1, 0]], dtype=bool)
    y = np.c_[signal, constant, roundoff, linear]
    assert informative_columns(y, basis, trend).tolist() == [0]
    alone = fit_lengthscales(z, y[:, :1], basis, trend[:1], "gaussian", NUGGET, restarts=2, seed=0)
    together = fit_lengthscales(z, y, basis, trend, "gaussian", NUGGET, restarts=2, seed=0)
    np.testing.assert_array_equal(together, alone)
    # with nothing to learn from, the start is returned
    start = np.array([0.3, 2.0])
    np.testing.assert_array_equal(fit_lengthscales(z, y[:, 1:], basis, trend[1:], "gaussian", NUGGET, 2, 0, start),
                                  start)
