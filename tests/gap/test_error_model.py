"""AR(1) error model: exact whitening (against the Cholesky factor of the covariance built here), draws with the
model covariance, the measurement-model scales, and bad input."""

import math

import numpy as np
import pytest
from scipy.linalg import cholesky, solve_triangular

from spflow.core.errors import ParameterError
from spflow.plugins.gap.error_model import BlockErrorModel, block_error_model
from spflow.plugins.gap.observed import load_experiments
from spflow.synthetic import NoiseModel, make_coreflood


def _stationary_cov(a, phi):
    n = a.size
    return np.array([[a[i] * a[j] * phi ** abs(i - j) for j in range(n)] for i in range(n)])


def _walk_cov(a):
    n = a.size
    return np.array([[np.sum(a[: min(i, j) + 1] ** 2) for j in range(n)] for i in range(n)])


@pytest.mark.parametrize("phi", [0.0, 0.35, 0.9])
def test_stationary_whitening_is_the_inverse_cholesky_factor(phi):
    rng = np.random.default_rng(1)
    a = rng.uniform(0.5, 3.0, 40)
    e = rng.normal(size=(40, 3))
    model = BlockErrorModel(a, phi)
    factor = cholesky(_stationary_cov(a, phi), lower=True)
    np.testing.assert_allclose(model.whiten(e), solve_triangular(factor, e, lower=True), rtol=1e-10, atol=1e-12)


def test_random_walk_whitening_is_the_inverse_cholesky_factor():
    rng = np.random.default_rng(2)
    a = rng.uniform(0.1, 1.0, 30)
    e = rng.normal(size=30)
    model = BlockErrorModel(a, 1.0)
    w = model.whiten(e)
    np.testing.assert_allclose(w, solve_triangular(cholesky(_walk_cov(a), lower=True), e, lower=True), rtol=1e-10)
    assert float(w @ w) == pytest.approx(float(e @ np.linalg.solve(_walk_cov(a), e)), rel=1e-9)
    np.testing.assert_allclose(model.marginal_std(), np.sqrt(np.diag(_walk_cov(a))), rtol=1e-12)


@pytest.mark.parametrize("phi", [0.6, 1.0])
def test_draws_have_the_model_covariance(phi):
    a = np.linspace(1.0, 2.0, 6)
    model = BlockErrorModel(a, phi)
    draws = model.draw(np.random.default_rng(3), 40000)
    expected = _walk_cov(a) if phi == 1.0 else _stationary_cov(a, phi)
    np.testing.assert_allclose(np.cov(draws.T), expected, atol=0.06 * expected.max())
    # whitening the draws gives iid standard normals
    w = model.whiten(draws.T)
    np.testing.assert_allclose(np.cov(w), np.eye(6), atol=0.03)


def test_bad_error_models_raise():
    with pytest.raises(ParameterError, match=r"phi = 1.5 is out of range; allowed \[0, 1\]"):
        BlockErrorModel(np.ones(3), 1.5)
    with pytest.raises(ParameterError, match="finite and > 0"):
        BlockErrorModel(np.array([1.0, 0.0]), 0.5)
    exp = load_experiments(["BCF1"], 0.1)[0]
    with pytest.raises(ParameterError, match="no error model for variable 'oil_volume'"):
        block_error_model("oil_volume", exp, np.ones(3))


def test_scales_follow_the_measurement_model():
    noise = NoiseModel(pressure_relative=0.03, pressure_ar1=0.7, pressure_interval_pv=0.02, tube_pv=0.05,
                       oil_resolution_ml=0.2)
    data = make_coreflood("BCF1", noise=noise, seed=0, cells=20)
    exp = load_experiments([data], 0.1)[0]
    dp = exp.observed["dp"][np.isfinite(exp.observed["dp"])]
    model = block_error_model("dp", exp, dp)
    assert model.phi == pytest.approx(0.7 ** 5)
    np.testing.assert_allclose(model.scale, 0.03 * np.maximum(np.abs(dp), 0.05 * np.abs(dp).max()))
    pv_ml = math.pi * 0.0508**2 / 4 * 0.1524 * 0.23 * 1e6  # default core, ml
    oil = block_error_model("oil_cut", exp, np.ones(4))
    # one 0.1 PV grid interval averages two 0.05 PV tubes, each read with a uniform error of width 0.2 ml
    np.testing.assert_allclose(oil.scale, 0.2 / math.sqrt(12) / (0.05 * pv_ml) / math.sqrt(2))
    rec = block_error_model("recovery", exp, np.ones(4))
    assert rec.phi == 1.0
    np.testing.assert_allclose(rec.scale, 0.2 / math.sqrt(12) / (pv_ml * 0.8) * math.sqrt(2))


def test_effluent_floor_follows_the_injected_concentration():
    """An effluent block that stays near zero (polymer held back) is floored at 5 % of the injected
    concentration times the assay's relative error, not at round-off size."""
    noise = NoiseModel(concentration_relative=0.03, tube_pv=0.05)
    data = make_coreflood("BCF1", noise=noise, seed=0, cells=20)
    exp = load_experiments([data], 0.1)[0]
    polymer_ppm = max(s.polymer_ppm for s in exp.schedule.slugs)
    assert polymer_ppm > 0
    near_zero = np.array([0.0, 1e-12, 3e-9, 2.0])
    model = block_error_model("c_polymer_out", exp, near_zero)
    # one 0.1 PV interval averages two 0.05 PV tubes: the assay error of the mean drops by sqrt(2)
    floor = 0.03 * 0.05 * polymer_ppm / math.sqrt(2)
    np.testing.assert_allclose(model.scale, floor)
    assert model.phi == 0.0
    # a block well above the floor keeps its relative error
    high = np.array([polymer_ppm, 0.5 * polymer_ppm])
    np.testing.assert_allclose(block_error_model("c_polymer_out", exp, high).scale, 0.03 * high / math.sqrt(2))
