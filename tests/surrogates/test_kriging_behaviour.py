"""What a noise-free Kriging proxy must do: interpolate its training data with ~zero variance there, grow its
variance away from the data, and -- with a polynomial trend -- reproduce a polynomial far from the data, where
ordinary Kriging (the plain GP) falls back to its constant mean."""

import numpy as np

from spflow.plugins.surrogates.basis import design_matrix, multi_indices
from spflow.plugins.surrogates.gp_model import GP
from spflow.plugins.surrogates.kriging import UniversalKriging
from spflow.plugins.surrogates.outputs import OutputIndex


def _index(m):
    return OutputIndex(np.array(["f"] * m), np.array([""] * m), np.full(m, np.nan), {"f": "1"})


def test_plain_gp_interpolates_and_its_variance_grows_away_from_the_data():
    rng = np.random.default_rng(3)
    lower, upper = np.array([0.0, 10.0]), np.array([2.0, 30.0])  # physical box, mapped to [-1, 1]^2
    x = lower + (upper - lower) * rng.uniform(size=(25, 2)) * [0.7, 1.0]  # no data at a > 1.4
    y = np.c_[np.sin(2 * x[:, 0]) * np.log(x[:, 1]), np.cos(3 * x[:, 0] + x[:, 1] / 10)]
    nugget = 1e-10
    model = GP.fit(["a", "b"], lower, upper, _index(2), x, y, restarts=2, seed=1, nugget=nugget)
    mean, var = model.predict(x)
    # noise-free up to the nugget: at the data the error is far below both the spread of y and the LOO error
    # (the error of predicting the same points without them), and the variance is about nugget x σ²
    loo_rms = np.sqrt(model.loo * np.var(y, axis=0))
    assert (np.abs(mean - y).max(axis=0) < np.minimum(1e-4 * y.std(axis=0), 0.1 * loo_rms)).all()
    assert (var <= 2 * nugget * model.process_variance).all()
    # moving away from a training point along a line, the variance increases monotonically at first
    direction = np.array([0.02, 0.2])
    steps = x[0] + np.outer(np.linspace(0.0, 1.0, 6), direction)
    inside = ((steps >= lower) & (steps <= upper)).all(axis=1)
    _, var_line = model.predict(steps[inside])
    assert inside.sum() >= 4 and (np.diff(var_line[:, 0]) > 0).all()
    # far from all the data (the edge a = 2) the variance is a noticeable fraction of σ² (10^7 x the nugget)
    _, var_far = model.predict(np.array([[2.0, 10.0], [2.0, 20.0], [2.0, 30.0]]))
    assert (var_far > 1e-3 * model.process_variance).all()


def test_polynomial_trend_reproduces_a_polynomial_far_from_the_data():
    rng = np.random.default_rng(4)
    z = rng.uniform(-1.0, -0.3, (15, 2))  # data in one corner of the box
    far = rng.uniform(0.5, 1.0, (10, 2))  # predictions in the opposite corner

    def poly(p):
        return 1.0 + 2.0 * p[:, 0] - 3.0 * p[:, 0] * p[:, 1] + 0.5 * p[:, 1] ** 2

    indices = multi_indices(2, 2)
    kernel, ell = "gaussian", np.array([0.4, 0.4])
    universal = UniversalKriging(z, poly(z)[:, None], design_matrix(z, indices), np.ones((1, 6), bool), kernel, ell, 1e-10)
    mean, var = universal.predict(far, design_matrix(far, indices))
    np.testing.assert_allclose(mean[:, 0], poly(far), rtol=1e-6, atol=1e-6)
    assert universal.process_variance[0] < 1e-12 * np.var(poly(z))  # the trend explains everything
    # ordinary Kriging on the same data reverts to its constant far away and misses the polynomial badly
    ordinary = UniversalKriging(z, poly(z)[:, None], np.ones((15, 1)), np.ones((1, 1), bool), kernel, ell, 1e-10)
    mean_ok, _ = ordinary.predict(far, np.ones((10, 1)))
    assert np.max(np.abs(mean_ok[:, 0] - poly(far))) > 1.0
