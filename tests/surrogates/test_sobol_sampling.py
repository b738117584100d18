"""Monte Carlo Sobol indices (``sobol_sampling.py``) and the Kriging estimators' ``sobol_indices`` against closed
forms derived here: Ishigami's partial variances (uniform inputs), an additive function and a product of independent
non-uniform inputs (normal, beta, lognormal: variances and moments of each law by hand); GP and PC-Kriging fitted on
Ishigami; PC-Kriging's trend indices recomputed from its coefficients; bad arguments refused."""

import numpy as np
import pytest
from scipy.stats import qmc

from spflow.core.errors import ParameterError
from spflow.plugins.surrogates.input_marginals import Beta, LogNormal, Normal, Uniform
from spflow.plugins.surrogates.sobol_sampling import pick_freeze_indices
from spflow.surrogates import GP, PCE, PCK

A, B = 7.0, 0.1
ISHIGAMI_BOX = [(-np.pi, np.pi)] * 3
CAP = "ignore::spflow.core.errors.DegreeCapWarning"  # PC-Kriging's degree-3 trend on Ishigami ends at its cap


def _ishigami(x):
    return np.sin(x[:, 0]) + A * np.sin(x[:, 1]) ** 2 + B * x[:, 2] ** 4 * np.sin(x[:, 0])


def _ishigami_indices():
    """(first, total) in closed form (Ishigami & Homma 1990; Sobol' & Levitan 1999): partial variances of
    X ~ U[-π, π]^3."""
    d1 = 0.5 * (1.0 + B * np.pi**4 / 5.0) ** 2
    d2 = A**2 / 8.0
    d13 = B**2 * np.pi**8 * (1.0 / 18.0 - 1.0 / 50.0)
    variance = d1 + d2 + d13
    return np.array([d1, d2, 0.0]) / variance, np.array([d1 + d13, d2, d13]) / variance


def test_ishigami_under_uniform_inputs_within_four_standard_errors():
    first, total = _ishigami_indices()
    out = pick_freeze_indices(_ishigami, [Uniform(-np.pi, np.pi)] * 3, n_base=2048, replicates=4, seed=3)
    assert out.first.shape == out.total.shape == out.first_se.shape == out.total_se.shape == (1, 3)
    assert (out.first_se > 0).all() and (out.total_se > 0).all()
    assert np.all(np.abs(out.first[0] - first) <= 4.0 * out.first_se[0])
    assert np.all(np.abs(out.total[0] - total) <= 4.0 * out.total_se[0])


def test_additive_and_product_functions_of_normal_beta_and_lognormal_inputs():
    # x1 ~ N(1, 0.5²), x2 ~ Beta(2, 3) on [0, 2], x3 ~ LogNormal(0, 0.25): moments by hand
    inputs = [Normal(1.0, 0.5), Beta(2.0, 3.0, 0.0, 2.0), LogNormal(0.0, 0.25)]
    m1, v1 = 1.0, 0.25
    m2, v2 = 2.0 * 2.0 / 5.0, 2.0**2 * 2.0 * 3.0 / (5.0**2 * 6.0)  # (u−l) α/(α+β), (u−l)² αβ/((α+β)²(α+β+1))
    m3, v3 = np.exp(0.25**2 / 2.0), (np.exp(0.25**2) - 1.0) * np.exp(0.25**2)
    a, b, c = 2.0, -3.0, 1.5

    def f(x):  # column 0 additive, column 1 the product x1 x3, column 2 constant (undefined indices)
        return np.column_stack([a * x[:, 0] + b * x[:, 1] + c * x[:, 2], x[:, 0] * x[:, 2], np.full(len(x), 4.0)])

    parts = np.array([a**2 * v1, b**2 * v2, c**2 * v3])
    additive = parts / parts.sum()  # S_i = S_Ti for an additive f
    # product of independent x1, x3: V1 = v1 m3², V3 = v3 m1², V13 = v1 v3
    p1, p3, p13 = v1 * m3**2, v3 * m1**2, v1 * v3
    vp = p1 + p3 + p13
    first = np.array([additive, [p1 / vp, 0.0, p3 / vp]])
    total = np.array([additive, [(p1 + p13) / vp, 0.0, (p3 + p13) / vp]])

    out = pick_freeze_indices(f, inputs, n_base=4096, replicates=4, seed=11)
    assert out.first.shape == (3, 3)
    assert np.isnan(out.first[2]).all() and np.isnan(out.total[2]).all()
    # x2 does not enter column 1: both estimators are exactly 0 there (f(A_B^(2)) = f(A))
    assert out.first[1, 1] == 0.0 and out.total[1, 1] == 0.0
    mask = np.ones((2, 3), dtype=bool)
    mask[1, 1] = False
    assert np.all(np.abs(out.first[:2] - first)[mask] <= 4.0 * out.first_se[:2][mask])
    assert np.all(np.abs(out.total[:2] - total)[mask] <= 4.0 * out.total_se[:2][mask])
    assert abs(first[0, 0] - 0.5) > 0.1  # the normal input's share is not that of a uniform of its range


@pytest.fixture(scope="module")
def ishigami_design():
    x = qmc.scale(qmc.LatinHypercube(d=3, rng=0).random(200), *np.array(ISHIGAMI_BOX).T)
    return x, _ishigami(x)


@pytest.mark.filterwarnings(CAP)
@pytest.mark.parametrize("estimator", [GP, PCK])
def test_kriging_predictor_indices_on_ishigami_at_n200(ishigami_design, estimator):
    x, y = ishigami_design
    model = estimator(ISHIGAMI_BOX, restarts=1).fit(x, y)
    first, total = _ishigami_indices()
    out = model.sobol_indices()  # the defaults: 8192 base points, 4 replicates
    assert out.first.shape == out.total.shape == out.first_se.shape == out.total_se.shape == (3,)
    np.testing.assert_allclose(out.first, first, atol=0.05)
    np.testing.assert_allclose(out.total, total, atol=0.05)
    assert (out.first_se < 0.01).all() and (out.total_se < 0.01).all()
    vector = estimator(ISHIGAMI_BOX, restarts=1).fit(x, np.column_stack([y, x[:, 1]]))
    out = vector.sobol_indices(n_base=256, replicates=2)
    assert out.first.shape == out.first_se.shape == (2, 3)
    np.testing.assert_allclose(out.first[1], [0.0, 1.0, 0.0], atol=0.02)  # the column x2 itself


@pytest.mark.filterwarnings(CAP)
def test_pck_trend_part_is_read_off_its_coefficients(ishigami_design):
    x, y = ishigami_design
    model = PCK(ISHIGAMI_BOX, restarts=1).fit(x, y)
    trend = model.sobol_indices(part="trend")
    assert trend.first_se is None and trend.total_se is None
    alpha, c2 = model.model_.indices, model.model_.coefficients[0] ** 2  # orthonormal basis: partial variances c²
    variance = c2[1:].sum()
    first = [c2[(alpha[:, i] > 0) & (alpha.sum(axis=1) == alpha[:, i])].sum() / variance for i in range(3)]
    total = [c2[alpha[:, i] > 0].sum() / variance for i in range(3)]
    np.testing.assert_allclose(trend.first, first, rtol=1e-12)
    np.testing.assert_allclose(trend.total, total, rtol=1e-12)
    assert abs(trend.first[0] - _ishigami_indices()[0][0]) > 0.1  # the trend alone is not the model here


def test_pce_indices_stay_analytic():
    x = qmc.scale(qmc.LatinHypercube(d=2, rng=1).random(30), [0.0, 0.0], [1.0, 2.0])
    out = PCE([(0.0, 1.0), (0.0, 2.0)]).fit(x, 3.0 * x[:, 0] + x[:, 1]).sobol_indices()
    assert out.first_se is None and out.total_se is None
    # V1 = 9/12, V2 = 4/12 (uniform variances (u − l)²/12)
    np.testing.assert_allclose(out.first, [9.0 / 13.0, 4.0 / 13.0], atol=1e-10)


@pytest.mark.parametrize("options, message", [
    ({"n_base": 100}, "n_base must be a power of 2 >= 64"),
    ({"n_base": 32}, "n_base must be a power of 2 >= 64"),
    ({"n_base": 128.0}, "n_base must be a power of 2 >= 64"),
    ({"n_base": True}, "n_base must be a power of 2 >= 64"),
    ({"replicates": 1}, "replicates must be an integer >= 2"),
    ({"seed": -1}, "seed must be a non-negative integer"),
])
def test_bad_sampling_arguments_are_refused_before_any_evaluation(options, message):
    calls = []

    def f(x):
        calls.append(len(x))
        return x[:, 0]

    with pytest.raises(ParameterError, match=message):
        pick_freeze_indices(f, [Uniform(0.0, 1.0)] * 2, **options)
    assert not calls


@pytest.mark.filterwarnings(CAP)
def test_bad_function_output_and_bad_part_are_refused(ishigami_design):
    with pytest.raises(ParameterError, match=r"must return shape \(n,\) or \(n, m\) for n = 64"):
        pick_freeze_indices(lambda x: x[:3, 0], [Uniform(0.0, 1.0)] * 2, n_base=64)
    with pytest.raises(ParameterError, match="non-finite"):
        pick_freeze_indices(lambda x: np.where(x[:, 0] > 0.5, np.inf, 0.0), [Uniform(0.0, 1.0)] * 2, n_base=64)
    x, y = ishigami_design
    gp = GP(ISHIGAMI_BOX, restarts=1).fit(x[:40], y[:40])
    with pytest.raises(ParameterError, match=r"GP.sobol_indices: n_base must be a power of 2 >= 64"):
        gp.sobol_indices(n_base=1000)
    with pytest.raises(ParameterError, match="part must be 'predictor'"):
        PCK(ISHIGAMI_BOX, degree_max=2, restarts=1).fit(x[:40], y[:40]).sobol_indices(part="gp")
    with pytest.raises(ParameterError, match="not fitted"):
        GP(ISHIGAMI_BOX).sobol_indices()
