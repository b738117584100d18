"""fit_least_squares against the closed form of (weighted) linear regression, computed here with numpy."""

import cf_units
import numpy as np
import pytest
from scipy import stats

from spflow.core.schema import DatasetSchema
from spflow.plugins.lab.fit_result import FIT, FitError, fit_interval, fit_least_squares, stated_interval


def _line_data(seed=0, n=25):
    rng = np.random.default_rng(seed)
    x = np.linspace(0.0, 4.0, n)
    y = 1.5 - 0.8 * x + rng.normal(0.0, 0.3, n)
    return x, y


def test_matches_ordinary_least_squares_closed_form():
    x, y = _line_data()
    fit = fit_least_squares(lambda t: t[0] + t[1] * x - y, [0.0, 0.0], names=["a", "b"], units=["cP", "Pa/s"],
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
    # units: as given in attrs, UDUNITS per parameter in 'unit' and per pair of parameters in 'covariance_units'
    assert fit.attrs["units_a"] == "cP" and fit.attrs["units_b"] == "Pa/s"
    products = [[cf_units.Unit(u) for u in row] for row in fit["covariance_units"].values]
    assert [cf_units.Unit(u) for u in fit["unit"].values] == [cf_units.Unit("mPa s"), cf_units.Unit("Pa s-1")]
    assert products == [[cf_units.Unit("mPa2 s2"), cf_units.Unit("mPa Pa")], [cf_units.Unit("mPa Pa"),
                                                                              cf_units.Unit("Pa2 s-2")]]
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


def _quadratic_data(seed=1, n=25):
    rng = np.random.default_rng(seed)
    x = np.linspace(0.0, 4.0, n)
    return x, 1.5 - 0.8 * x + 0.3 * x**2 + rng.normal(0.0, 0.3, n)


@pytest.mark.parametrize("known", [False, True])
def test_profile_interval_equals_exact_interval_of_a_linear_model(known):
    # y = a + b x + c x^2: the profiled RSS of each coefficient is an exact parabola, so the profile interval is the
    # exact t-interval (estimated noise) or normal interval (known sigma), computed here in closed form.
    x, y = _quadratic_data()
    sigma = 0.1 + 0.1 * x if known else None
    fit = fit_least_squares(lambda t: t[0] + t[1] * x + t[2] * x**2 - y, [0.0, 0.0, 0.0], names=["a", "b", "c"],
                            units=["1"] * 3, bounds=[(None, None)] * 3, sigma=sigma, profile=True, level=0.9)
    X = np.column_stack([np.ones_like(x), x, x**2])
    w = np.ones_like(x) if sigma is None else 1.0 / sigma
    Xw, yw = X * w[:, None], y * w
    beta, rss = np.linalg.lstsq(Xw, yw, rcond=None)[:2]
    s2 = 1.0 if known else rss[0] / (x.size - 3)
    q = stats.norm.ppf(0.95) if known else stats.t.ppf(0.95, x.size - 3)
    half = q * np.sqrt(s2 * np.diag(np.linalg.inv(Xw.T @ Xw)))
    np.testing.assert_allclose(fit["profile_lower"].values, beta - half, rtol=1e-6, atol=1e-9)
    np.testing.assert_allclose(fit["profile_upper"].values, beta + half, rtol=1e-6, atol=1e-9)
    assert fit.attrs["stated_interval"] == "profile" and fit.attrs["interval_level"] == 0.9
    lo, hi = stated_interval(fit)
    np.testing.assert_allclose(hi.values - lo.values, 2 * half, rtol=1e-6)
    FIT.validate(fit, stage="test", port="out")


def test_profile_interval_ends_at_a_bound_that_cuts_it():
    # the bound a >= 1.45 lies inside the exact interval of the intercept: the lower end is the bound, the upper end
    # the exact one (the slope stays free, so the profile of a is still the parabola above the bound)
    x, y = _line_data()
    X = np.column_stack([np.ones_like(x), x])
    beta, rss = np.linalg.lstsq(X, y, rcond=None)[:2]
    half = stats.t.ppf(0.975, x.size - 2) * np.sqrt(rss[0] / (x.size - 2) * np.linalg.inv(X.T @ X)[0, 0])
    low = beta[0] - 0.5 * half
    fit = fit_least_squares(lambda t: t[0] + t[1] * x - y, [beta[0], 0.0], names=["a", "b"], units=["1", "1"],
                            bounds=[(low, None), (None, None)], profile=True)
    assert fit["profile_lower"].sel(param="a") == low
    assert float(fit["profile_upper"].sel(param="a")) == pytest.approx(beta[0] + half, rel=1e-6)


def test_profile_interval_of_a_nonlinear_model_matches_brute_force_profile():
    # y = A exp(-k t) with k <= 1.45: at the lower end of the profile interval of k the RSS minimised over A (here by
    # minimize_scalar, independently of least_squares) equals the F threshold; the upper end is the bound 1.45,
    # where the profile is still below it; inside, the profile stays below; the end differs from the linearised one
    from scipy.optimize import minimize_scalar

    rng = np.random.default_rng(11)
    t = np.linspace(0, 1.0, 12)
    y = 2.0 * np.exp(-1.3 * t) + rng.normal(0, 0.08, t.size)
    fit = fit_least_squares(lambda p: p[0] * np.exp(-p[1] * t) - y, [1.0, 1.0], names=["A", "k"], units=["1", "1/s"],
                            bounds=[(0, None), (0, 1.45)], profile=True)
    dof = t.size - 2
    threshold = fit.attrs["rss"] * (1 + stats.t.ppf(0.975, dof) ** 2 / dof)
    assert fit.attrs["profile_threshold_rss"] == pytest.approx(threshold, rel=1e-12)

    def profiled(k):
        return minimize_scalar(lambda a: np.sum((a * np.exp(-k * t) - y) ** 2), bounds=(0, 10), method="bounded",
                               options={"xatol": 1e-12}).fun

    k_lo, k_hi = float(fit["profile_lower"].sel(param="k")), float(fit["profile_upper"].sel(param="k"))
    assert profiled(k_lo) == pytest.approx(threshold, rel=1e-7)
    assert profiled(k_lo - 1e-3) > threshold
    assert k_hi == 1.45 and profiled(1.45) < threshold
    assert all(profiled(k) < threshold for k in np.linspace(k_lo, k_hi, 41)[1:])
    lo, _ = fit_interval(fit)
    assert abs(float(lo.sel(param="k")) - k_lo) > 1e-3  # curvature: not the linearised end (1.1736 vs 1.1761)


def test_stated_interval_is_linearised_unless_profiled():
    x, y = _line_data()
    fit = fit_least_squares(lambda t: t[0] + t[1] * x - y, [0.0, 0.0], names=["a", "b"], units=["1", "1"],
                            bounds=[(None, None)] * 2)
    assert fit.attrs["stated_interval"] == "linearised" and "profile_lower" not in fit
    lo, hi = stated_interval(fit)
    lo2, hi2 = fit_interval(fit, 0.95)
    np.testing.assert_array_equal(lo.values, lo2.values)
    np.testing.assert_array_equal(hi.values, hi2.values)
    with pytest.raises(FitError, match=r"level = 1.5 must be in \(0, 1\)"):
        fit_least_squares(lambda t: t[0] + t[1] * x - y, [0.0, 0.0], names=["a", "b"], units=["1", "1"],
                          bounds=[(None, None)] * 2, profile=True, level=1.5)


def test_exact_fit_has_zero_width_profile_interval():
    x = np.linspace(0.0, 4.0, 9)
    fit = fit_least_squares(lambda t: t[0] + t[1] * x - (1.0 + 2.0 * x), [1.0, 2.0], names=["a", "b"],
                            units=["1", "1"], bounds=[(None, None)] * 2, profile=True)
    assert fit.attrs["rss"] == 0.0
    np.testing.assert_array_equal(fit["profile_lower"].values, [1.0, 2.0])
    np.testing.assert_array_equal(fit["profile_upper"].values, [1.0, 2.0])
