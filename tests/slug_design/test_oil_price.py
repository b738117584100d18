"""Stochastic oil price model (Eq. 4.12): moments of log S(t) over many seeds against the random-walk law."""

import numpy as np
import pytest
from scipy import stats

from spflow.core.errors import ParameterError
from spflow.plugins.slug_design.oil_price import OilPriceModel


@pytest.mark.parametrize("alpha, mu", [(1e-4, 1e-5), (1e-4, -1e-5), (2e-2, 3e-3)])
def test_log_price_mean_and_variance_over_many_seeds(alpha, mu):
    """log S(t_k) ~ N(log S0 + mu k, alpha^2 k): sample mean within 4 standard errors, variance by a chi^2 bound."""
    model = OilPriceModel(s0=75.0, alpha=alpha, mu=mu, steps_per_year=20)
    n = 1500
    logs = np.log(np.vstack([model.paths(13, 1, rng=seed)[0] for seed in range(n)]))
    k = np.arange(13 * 20 + 1)
    for step in (20, 100, 260):
        sample = logs[:, step]
        mean, var = np.log(75.0) + mu * k[step], alpha ** 2 * k[step]
        assert abs(sample.mean() - mean) < 4.0 * np.sqrt(var / n)
        low, high = stats.chi2.ppf([1e-4, 1 - 1e-4], n - 1) / (n - 1)
        assert low * var < sample.var(ddof=1) < high * var
    assert np.all(logs[:, 0] == np.log(75.0))


def test_increments_are_independent_gaussians():
    model = OilPriceModel(alpha=1e-3, mu=2e-4, steps_per_year=200)
    dw = np.diff(model.log_paths(10, 3, rng=7), axis=1)
    z = ((dw - 2e-4) / 1e-3).ravel()
    assert stats.kstest(z, "norm").pvalue > 1e-3
    lag1 = np.corrcoef(dw[:, :-1].ravel(), dw[:, 1:].ravel())[0, 1]
    assert abs(lag1) < 4.0 / np.sqrt(z.size)


def test_seeded_paths_repeat_and_annual_prices_are_year_ends():
    model = OilPriceModel(mu=-1e-5)
    a, b = model.paths(13, 2, rng=11), model.paths(13, 2, rng=11)
    np.testing.assert_array_equal(a, b)
    assert not np.array_equal(a, model.paths(13, 2, rng=12))
    t = model.times(13)
    years = model.annual_prices(13, 2, rng=11)
    assert years.shape == (2, 13)
    ends = [int(np.flatnonzero(np.isclose(t, j))[0]) for j in range(1, 14)]
    np.testing.assert_array_equal(years, a[:, ends])


def test_zero_volatility_is_the_deterministic_drift():
    model = OilPriceModel(alpha=0.0, mu=1e-5, steps_per_year=365)
    path = model.paths(13, 1, rng=0)[0]
    np.testing.assert_allclose(path, 75.0 * np.exp(1e-5 * np.arange(path.size)), rtol=1e-12)
    assert model.annual_log_drift == pytest.approx(365e-5)
    assert OilPriceModel().annual_log_volatility == pytest.approx(1e-4 * np.sqrt(365))


@pytest.mark.parametrize("kwargs, field", [
    ({"s0": -1.0}, "s0"), ({"alpha": float("nan")}, "alpha"), ({"alpha": -1e-4}, "alpha"), ({"mu": 2.0}, "mu"),
    ({"steps_per_year": 0}, "steps_per_year"), ({"steps_per_year": 2.5}, "steps_per_year"),
])
def test_bad_fields_are_named(kwargs, field):
    with pytest.raises(ParameterError, match=rf"'{field}'.*(range|allowed|integer in)"):
        OilPriceModel(**kwargs)


def test_bad_horizon_and_path_count():
    with pytest.raises(ParameterError, match="years"):
        OilPriceModel().paths(0)
    with pytest.raises(ParameterError, match="n_paths"):
        OilPriceModel().paths(13, 0)
