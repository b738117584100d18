"""Convergence diagnostics on chains with known properties: iid normal draws and stationary AR(1) chains (whose
integrated autocorrelation time (1 + φ)/(1 − φ) and autocorrelation φ^k are known)."""

import numpy as np
import pytest
import xarray as xr
from scipy.signal import lfilter

from spflow.core.errors import ParameterError
from spflow.plugins.calibration.diagnostics import (autocorrelation, geweke, geweke_intervals, independent_series,
                                                    integrated_time, summary)


def _ar1(rng, phi, n, chains=None):
    """Stationary AR(1) with unit innovations: start drawn from N(0, 1/(1-φ²))."""
    shape = (n,) if chains is None else (chains, n)
    e = rng.normal(size=shape)
    e[..., 0] /= np.sqrt(1 - phi**2)
    return lfilter([1.0], [1.0, -phi], e, axis=-1)


def _naive_geweke(x, first=0.1, last=0.5):
    """The thesis's Eq. E.1 / old PyMC3 form: plain variances of the two segments."""
    n = x.size
    a, b = x[: int(first * n)], x[n - int(last * n):]
    return (a.mean() - b.mean()) / np.sqrt(a.var() / a.size + b.var() / b.size)


def test_geweke_on_iid_draws_is_standard_normal():
    rng = np.random.default_rng(0)
    z = np.array([geweke(rng.normal(size=2000)) for _ in range(300)])
    assert np.mean(np.abs(z) < 2) > 0.92  # 95.4 % expected
    assert 0.85 < z.std() < 1.15


def test_geweke_uses_the_spectral_variance_on_autocorrelated_chains():
    """On AR(1) with φ = 0.9 (τ = 19) plain variances give z with spread ≈ sqrt(19) ≈ 4.4; the spectral form stays
    near 1. With plain variances this test fails."""
    rng = np.random.default_rng(1)
    chains = [_ar1(rng, 0.9, 5000) for _ in range(200)]
    spectral = np.array([geweke(x) for x in chains])
    naive = np.array([_naive_geweke(x) for x in chains])
    assert naive.std() > 3.0  # the reference: plain variances are far too small
    assert 0.8 < spectral.std() < 1.4
    assert np.mean(np.abs(spectral) < 2) > 0.85
    # chain by chain, the spectral z is the naive one shrunk by about 1/sqrt(τ)
    ratio = np.median(np.abs(spectral / naive))
    assert ratio == pytest.approx(1 / np.sqrt(19.0), rel=0.25)


def test_geweke_detects_a_drifting_chain():
    rng = np.random.default_rng(2)
    x = rng.normal(size=4000) + np.linspace(1.0, 0.0, 4000)  # not stationary: mean drifts from 1 to 0
    assert abs(geweke(x)) > 5


def test_geweke_pools_chains_as_replicas():
    rng = np.random.default_rng(3)
    z = np.array([geweke(_ar1(rng, 0.8, 2000, chains=4)) for _ in range(150)])
    assert 0.8 < z.std() < 1.3


def test_geweke_intervals_start_further_in():
    rng = np.random.default_rng(4)
    starts, z = geweke_intervals(rng.normal(size=1000), intervals=5)
    np.testing.assert_array_equal(starts, [0, 125, 250, 375, 500])
    assert z.shape == (5,) and np.all(np.isfinite(z))


def test_geweke_rejects_bad_segments():
    with pytest.raises(ParameterError, match="first"):
        geweke(np.zeros(100), first=0.6, last=0.5)


def test_integrated_time_and_autocorrelation_of_ar1():
    rng = np.random.default_rng(5)
    phi = 0.7
    x = _ar1(rng, phi, 20000, chains=4)
    assert integrated_time(x) == pytest.approx((1 + phi) / (1 - phi), rel=0.1)
    np.testing.assert_allclose(autocorrelation(x, 5), phi ** np.arange(6), atol=0.03)


def _posterior(theta, chain_run=None):
    ds = xr.Dataset({"theta": (("chain", "draw", "param"), theta, {"units": "1"})},
                    coords={"chain": np.arange(theta.shape[0]), "draw": np.arange(theta.shape[1]),
                            "param": [f"p{k}" for k in range(theta.shape[2])]})
    if chain_run is not None:
        ds = ds.assign_coords(chain_run=("chain", chain_run))
    return ds


def test_summary_flags_chains_that_disagree():
    rng = np.random.default_rng(6)
    theta = rng.normal(size=(4, 1000, 2))
    theta[3, :, 1] += 3.0  # one chain elsewhere in the second parameter
    table = summary(_posterior(theta))
    assert table["rhat"].sel(param="p0") < 1.01 and table["rhat"].sel(param="p1") > 1.2
    assert 3000 < table["ess_bulk"].sel(param="p0") < 5000  # iid: about chains x draws
    np.testing.assert_allclose(table["mean"].values, theta.mean(axis=(0, 1)))
    np.testing.assert_allclose(table["q975"].values, np.quantile(theta, 0.975, axis=(0, 1)))


def test_independent_series_averages_the_walkers_of_each_run():
    theta = np.arange(4 * 3 * 1, dtype=float).reshape(4, 3, 1)
    series = independent_series(_posterior(theta, chain_run=[0, 0, 1, 1]))
    np.testing.assert_array_equal(series[:, :, 0], [theta[:2, :, 0].mean(0), theta[2:, :, 0].mean(0)])
    np.testing.assert_array_equal(independent_series(_posterior(theta)), theta)
