"""fit_least_squares against the closed form of (weighted) linear regression, computed here with numpy."""

import numpy as np
import pytest
from scipy import stats

from spflow.core.schema import DatasetSchema
from spflow.plugins.lab.fit_result import FIT, FitError, fit_interval, fit_least_squares


def _line_data(seed=0, n=25):
    rng = np.random.default_rng(seed)
    x = np.linspace(0.0, 4.0, n)
    y = 1.5 - 0.8 * x + rng.normal(0.0, 0.3, n)
    return x, y


def test_matches_ordinary_least_squares_closed_form():
    x, y = _line_data()
    fit = fit_least_squares(lambda t: t[0] + t[1] * x - y, [0.0, 0.0], names=["a", "b"], units=["cP", "cP/s"],
                            bounds=[(None, None), (-10.0, 10.0)], experiment="line", kind="test")
    X = np.column_stack([np.ones_like(x), x])
    beta = np.linalg.solve(X.T @ X, X.T @ y)
    resid = y - X @ beta
    s2 = resid @ resid / (x.size - 2)
    cov = s2 * np.linalg.inv(X.T @ X)
    np.testing.assert_allclose(fit["estimate"].values, beta, rtol=1e-8, atol=1e-10)
    np.testing.assert_allclose(fit["covariance"].values, cov, rtol=1e-5)
    np.testing.assert_allclose(fit["std"].values, np.sqrt(np.diag(cov)), rtol=1e-5)
    assert fit.attrs["dof"] == x.size - 2 and fit.attrs["n_points"] == x.size
    assert fit.attrs["rss"] == pytest.approx(resid @ resid, rel=1e-8)
    assert fit.attrs["units_b"] == "cP/s" and list(fit["unit"].values) == ["cP", "cP/s"]
    FIT.validate(fit, stage="test", port="out")
    lo, hi = fit_interval(fit, 0.95)
    q = stats.t.ppf(0.975, x.size - 2)
    np.testing.assert_allclose(hi.values - lo.values, 2 * q * np.sqrt(np.diag(cov)), rtol=1e-5)


def test_matches_weighted_least_squares_with_known_sigma():
    x, y = _line_data(seed=3)
    sigma = 0.1 + 0.2 * x
    fit = fit_least_squares(lambda t: t[0] + t[1] * x - y, [0.0, 0.0], names=["a", "b"], units=["1", "1"],
                            bounds=[(None, None), (None, None)], sigma=sigma)
    X = np.column_stack([np.ones_like(x), x])
    W = np.diag(1.0 / sigma**2)
    cov = np.linalg.inv(X.T @ W @ X)
    beta = cov @ X.T @ W @ y
    np.testing.assert_allclose(fit["estimate"].values, beta, rtol=1e-8, atol=1e-10)
    np.testing.assert_allclose(fit["covariance"].values, cov, rtol=1e-5)
    assert fit.attrs["noise"] == "known"
    assert fit.attrs["reduced_chi2"] == pytest.approx(((X @ beta - y) ** 2 / sigma**2).sum() / (x.size - 2))
    lo, hi = fit_interval(fit, 0.9)
    np.testing.assert_allclose(hi.values - fit["estimate"].values, stats.norm.ppf(0.95) * np.sqrt(np.diag(cov)),
                               rtol=1e-5)


def test_nonlinear_exponential_covariance_matches_linearised_jacobian():
    # y = A exp(-k t): covariance at the optimum equals s^2 (J^T J)^-1 with the analytic Jacobian.
    rng = np.random.default_rng(7)
    t = np.linspace(0, 3, 30)
    y = 2.0 * np.exp(-1.3 * t) + rng.normal(0, 0.02, t.size)
    fit = fit_least_squares(lambda p: p[0] * np.exp(-p[1] * t) - y, [1.0, 1.0], names=["A", "k"], units=["1", "1/s"],
                            bounds=[(0, None), (0, None)])
    A, k = fit["estimate"].values
    J = np.column_stack([np.exp(-k * t), -A * t * np.exp(-k * t)])
    r = A * np.exp(-k * t) - y
    assert np.abs(J.T @ r).max() < 1e-8  # stationary point of the sum of squares
    cov = (r @ r / (t.size - 2)) * np.linalg.inv(J.T @ J)
    np.testing.assert_allclose(fit["covariance"].values, cov, rtol=1e-4)


def test_unidentifiable_parameters_raise():
    x = np.linspace(0, 1, 10)
    with pytest.raises(FitError, match="not identifiable"):
        fit_least_squares(lambda t: (t[0] + t[1]) * x - 2 * x, [0.5, 0.5], names=["a", "b"], units=["1", "1"],
                          bounds=[(None, None), (None, None)])


@pytest.mark.parametrize(
    "kwargs, match",
    [
        (dict(x0=[0.0]), "x0 has shape"),
        (dict(units=["1"]), "units: 1 entries"),
        (dict(bounds=[(0, 1)]), "bounds: 1"),
        (dict(bounds=[(1, 0), (None, None)]), "low 1.0 must be < high 0.0"),
        (dict(x0=[5.0, 0.0], bounds=[(0, 1), (None, None)]), "starting value of 'a'"),
        (dict(sigma=[1.0, 2.0]), "sigma must be"),
        (dict(sigma=-1.0), "sigma must be"),
        (dict(names=["a", "a"]), "unique"),
    ],
)
def test_bad_inputs_raise_before_fitting(kwargs, match):
    x = np.linspace(0, 1, 6)
    base = dict(x0=[0.0, 0.0], names=["a", "b"], units=["1", "1"], bounds=[(None, None), (None, None)])
    base.update(kwargs)
    with pytest.raises(FitError, match=match):
        fit_least_squares(lambda t: t[0] + t[1] * x - x, **base)


def test_too_few_points_raise():
    x = np.array([0.0, 1.0])
    with pytest.raises(FitError, match="need more data points"):
        fit_least_squares(lambda t: t[0] + t[1] * x, [0, 0], names=["a", "b"], units=["1", "1"],
                          bounds=[(None, None)] * 2)


def test_fit_schema_is_a_dataset_schema():
    assert isinstance(FIT, DatasetSchema) and "param" in FIT.dims
