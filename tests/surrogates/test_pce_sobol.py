"""Moments and Sobol indices read off PCE coefficients (thesis Eqs. 3.11-3.12; Sudret 2008) against the analytic
values of the Ishigami and Sobol G functions (OLS at high degree and hybrid LARS), and of a polynomial."""

import numpy as np
import pytest
from oracles.sensitivity_benchmarks import ishigami, ishigami_moments, sobol_g, sobol_g_moments
from scipy.stats import qmc

from spflow.core.errors import ParameterError
from spflow.plugins.surrogates import sobol_from_pce as sobol
from spflow.plugins.surrogates.outputs import OutputIndex
from spflow.plugins.surrogates.pce_model import PCE

ONE = OutputIndex(np.array(["f"]), np.array([""]), np.array([np.nan]), {"f": "1"})
NAMES = ["x1", "x2", "x3"]


def _ishigami_pce(n, **options):
    lo, hi = [-np.pi] * 3, [np.pi] * 3
    x = qmc.scale(qmc.LatinHypercube(d=3, rng=1).random(n), lo, hi)
    return PCE.fit(NAMES, lo, hi, ONE, x, ishigami(x), **options)


@pytest.mark.parametrize("n, options", [
    (800, {"solver": "ols", "degree_max": 16, "q": 0.75}),
    (300, {"solver": "lars", "degree_max": 14, "q": 0.75}),
])
def test_ishigami_moments_and_indices(n, options):
    ref = ishigami_moments()
    model = _ishigami_pce(n, **options)
    mean, variance = model.moments()
    assert abs(mean[0] - ref["mean"]) < 0.01
    assert abs(variance[0] - ref["variance"]) < 0.01
    indices = model.sobol()
    np.testing.assert_allclose(indices["S1"].values[0], ref["S"], atol=0.01)
    np.testing.assert_allclose(indices["ST"].values[0], ref["ST"], atol=0.01)
    assert abs(model.group_sobol(["x1", "x3"])[0] - ref["S13"]) < 0.01
    assert abs(model.group_sobol(["x1", "x2"])[0]) < 0.01  # no x1-x2 interaction in Ishigami
    closed = model.group_sobol(["x1", "x3"], closed=True)[0]
    assert abs(closed - (ref["S"][0] + ref["S"][2] + ref["S13"])) < 0.01


def test_g_function_indices_with_lars():
    a = np.array([0.0, 1.0, 4.5, 9.0, 99.0, 99.0, 99.0, 99.0])
    ref = sobol_g_moments(a)
    x = qmc.LatinHypercube(d=8, rng=2).random(300)
    names = [f"x{i}" for i in range(8)]
    # q = 0.5 favours high univariate degrees: the kink of |4 x1 - 2| needs them, interactions are weak
    model = PCE.fit(names, np.zeros(8), np.ones(8), ONE, x, sobol_g(x, a), solver="lars", degree_max=12, q=0.5)
    indices = model.sobol()
    np.testing.assert_allclose(indices["S1"].values[0], ref["S"], atol=0.02)
    np.testing.assert_allclose(indices["ST"].values[0], ref["ST"], atol=0.02)


def test_polynomial_exact_moments_and_indices():
    # f = 1 + 2 x1 + 3 x2^2 + x1 x2 on [-1, 1]^2 with x uniform: E[x^2] = 1/3, Var(x^2) = 4/45
    rng = np.random.default_rng(0)
    x = rng.uniform(-1, 1, (60, 2))
    f = 1 + 2 * x[:, 0] + 3 * x[:, 1] ** 2 + x[:, 0] * x[:, 1]
    model = PCE.fit(["a", "b"], [-1, -1], [1, 1], ONE, x, f, solver="ols", degree_max=3, q=1.0)
    d1, d2, d12 = 4 / 3, 9 * 4 / 45, 1 / 9
    mean, variance = model.moments()
    np.testing.assert_allclose([mean[0], variance[0]], [2.0, d1 + d2 + d12], rtol=1e-10)
    total = d1 + d2 + d12
    np.testing.assert_allclose(model.sobol()["S1"].values[0], [d1 / total, d2 / total], rtol=1e-9)
    np.testing.assert_allclose(model.sobol()["ST"].values[0], [(d1 + d12) / total, (d2 + d12) / total], rtol=1e-9)


def test_vectorised_over_outputs_and_bad_input():
    idx = np.array([[0, 0], [1, 0], [0, 1], [1, 1]])
    coef = np.array([[1.0, 1.0, 1.0, 1.0], [0.0, 0.0, 2.0, 0.0]])
    np.testing.assert_allclose(sobol.first_order(idx, coef), [[1 / 3, 1 / 3], [0.0, 1.0]])
    np.testing.assert_allclose(sobol.total_order(idx, coef), [[2 / 3, 2 / 3], [0.0, 1.0]])
    with pytest.raises(ParameterError, match="constant term"):
        sobol.moments(idx[::-1], coef)
    with pytest.raises(ParameterError, match="must match"):
        sobol.moments(idx, coef[:, :3])
    with pytest.raises(ParameterError, match="group"):
        sobol.group_index(idx, coef, [0, 2])
