"""Hybrid LARS (Blatman & Sudret 2011): exact support recovery of sparse polynomials, OLS refits and modified LOO
along the path equal to independent recomputation, one LARS per output column."""

import numpy as np
import pytest

from spflow.core.errors import ParameterError
from spflow.plugins.surrogates.basis import design_matrix, multi_indices
from spflow.plugins.surrogates.degree_adaptive import fit_pce
from spflow.plugins.surrogates.lars import hybrid_lars, hybrid_lars_outputs
from spflow.plugins.surrogates.regression import ols


def _basis(n=120, d=5, p=4, seed=0):
    z = np.random.default_rng(seed).uniform(-1, 1, (n, d))
    return design_matrix(z, multi_indices(d, p, 1.0))


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_recovers_exact_support_of_sparse_polynomial(seed):
    psi = _basis(seed=seed)
    rng = np.random.default_rng(10 + seed)
    support = np.concatenate([[0], rng.choice(np.arange(1, psi.shape[1]), 6, replace=False)])
    truth = np.zeros(psi.shape[1])
    truth[support] = rng.choice([-1, 1], support.size) * rng.uniform(0.5, 2.0, support.size)
    result = hybrid_lars(psi, psi @ truth)
    assert sorted(result.active) == sorted(support)
    assert result.active[0] == 0
    np.testing.assert_allclose(result.coefficients, truth, atol=1e-10)
    assert result.modified_loo < 1e-20


@pytest.mark.parametrize("scale", [1e-12, 1e-6, 1e6])
def test_recovers_a_sparse_polynomial_whatever_the_units_of_y(scale):
    """scikit-learn's path stops on an absolute threshold (1.2e-7 in y's units); the ranking must not see the units:
    the same polynomial in 'small' or 'large' units is recovered term for term (before the fix, 1e-12 gave the
    constant alone)."""
    psi = _basis(seed=3)
    rng = np.random.default_rng(13)
    support = np.concatenate([[0], rng.choice(np.arange(1, psi.shape[1]), 6, replace=False)])
    truth = np.zeros(psi.shape[1])
    truth[support] = scale * rng.choice([-1, 1], support.size) * rng.uniform(0.5, 2.0, support.size)
    result = hybrid_lars(psi, psi @ truth)
    assert sorted(result.active) == sorted(support)
    np.testing.assert_allclose(result.coefficients, truth, rtol=0, atol=1e-10 * scale)


def test_selected_model_is_the_ols_refit_with_its_errors():
    psi = _basis(seed=4)
    z1 = psi[:, 1]
    y = np.tanh(2 * z1) + 0.3 * psi[:, 7] * psi[:, 2] + 0.02 * np.random.default_rng(5).normal(size=psi.shape[0])
    result = hybrid_lars(psi, y)
    refit = ols(psi[:, result.active], y)
    np.testing.assert_allclose(result.coefficients[result.active], refit.coefficients, rtol=1e-8, atol=1e-12)
    assert np.count_nonzero(result.coefficients) == result.active.size
    np.testing.assert_allclose([result.loo, result.modified_loo, result.empirical],
                               [refit.loo, refit.modified_loo, refit.empirical], rtol=1e-8)
    # the scored path: prefix k of the LARS order refitted by OLS; the selection is its minimum
    for k in range(result.active.size):
        np.testing.assert_allclose(result.path_modified_loo[k], ols(psi[:, result.active[: k + 1]], y).modified_loo,
                                   rtol=1e-8)
    assert result.modified_loo == result.path_modified_loo.min()


def test_first_regressor_is_the_most_correlated_one():
    psi = _basis(seed=6)
    y = np.sin(3 * psi[:, 2]) + 0.5 * psi[:, 9]
    centred = psi[:, 1:] - psi[:, 1:].mean(axis=0)
    corr = np.abs(centred.T @ (y - y.mean())) / np.linalg.norm(centred, axis=0)
    assert hybrid_lars(psi, y).active[1] == 1 + int(np.argmax(corr))


def test_vector_outputs_are_independent_fits():
    psi = _basis(seed=7)
    y = np.column_stack([psi[:, 3] + 0.1 * psi[:, 20], np.cos(psi[:, 1]), psi[:, 5] * 2.0])
    many = hybrid_lars_outputs(psi, y)
    for j, result in enumerate(many):
        single = hybrid_lars(psi, y[:, j])
        np.testing.assert_array_equal(result.active, single.active)
        np.testing.assert_allclose(result.coefficients, single.coefficients, rtol=1e-12, atol=1e-14)


def test_at_most_n_minus_1_terms_and_constant_output():
    psi = _basis(n=25, p=4)  # 126 candidate terms, 25 points
    y = np.exp(psi[:, 1]) * psi[:, 2]
    result = hybrid_lars(psi, y)
    assert result.active.size <= 24 and np.isfinite(result.modified_loo)
    constant = hybrid_lars(psi, np.full(25, 3.0))
    np.testing.assert_array_equal(constant.active, [0])
    assert constant.coefficients[0] == pytest.approx(3.0) and constant.modified_loo == 0.0


def test_bad_input():
    psi = _basis()
    with pytest.raises(ParameterError, match="constant column"):
        hybrid_lars(psi[:, 1:], psi[:, 1])
    with pytest.raises(ParameterError, match="shape"):
        hybrid_lars(psi, psi[:10, 1])
    with pytest.raises(ParameterError, match="shape"):
        hybrid_lars_outputs(psi, psi[:, 1])
    with pytest.raises(ParameterError, match="finite"):
        hybrid_lars(psi, np.full(psi.shape[0], np.inf))


def _lar_entry_order(x, y, steps):
    """Plain least-angle regression written out here from Efron, Hastie, Johnstone & Tibshirani (2004, §2,
    Eqs. 2.4-2.13): the order in which the columns of ``x`` (centred, equal norms) enter the active set."""
    active, mu = [int(np.argmax(np.abs(x.T @ y)))], np.zeros(y.size)
    while len(active) < steps:
        c = x.T @ (y - mu)
        big_c = np.abs(c[active]).max()
        xa = x[:, active] * np.sign(c[active])
        g_inv_1 = np.linalg.solve(xa.T @ xa, np.ones(len(active)))
        a_a = 1.0 / np.sqrt(g_inv_1.sum())
        u = xa @ (a_a * g_inv_1)  # the equiangular direction
        a = x.T @ u
        gamma = np.full(x.shape[1], np.inf)
        for j in set(range(x.shape[1])) - set(active):
            steps_j = [(big_c - c[j]) / (a_a - a[j]), (big_c + c[j]) / (a_a + a[j])]
            gamma[j] = min(s for s in steps_j if s > 1e-12 * big_c / a_a)
        active.append(int(np.argmin(gamma)))
        mu += gamma[active[-1]] * u
    return active


@pytest.mark.parametrize("seed", [2, 5])
def test_plain_lar_ranking_is_the_entry_order_of_least_angle_regression(seed):
    psi = _basis(n=200, d=4, p=3, seed=20 + seed)  # 34 candidate terms, well conditioned
    rng = np.random.default_rng(30 + seed)
    truth = np.zeros(psi.shape[1])
    support = rng.choice(np.arange(1, psi.shape[1]), 18, replace=False)
    truth[support] = rng.uniform(0.2, 2.0, 18) * rng.choice([-1, 1], 18)
    y = psi @ truth + 0.3 * np.tanh(3.0 * psi[:, 1])  # not a polynomial: the path runs past the support
    x = psi[:, 1:] - psi[:, 1:].mean(axis=0)
    x /= np.linalg.norm(x, axis=0)
    expected = 1 + np.array(_lar_entry_order(x, y - y.mean(), x.shape[1] - 1))
    lar = hybrid_lars(psi, y, ranking="lar").active
    # the selected model is a prefix of the ranking: constant, then the reference's entry order
    assert lar[0] == 0 and lar.size > 15
    np.testing.assert_array_equal(lar[1:], expected[: lar.size - 1])
    # on these designs a regressor leaves the LASSO path (and re-enters later or never): its ranking differs
    lasso = hybrid_lars(psi, y).active
    assert not np.array_equal(lasso[1:], expected[: lasso.size - 1])


def test_unknown_ranking_is_refused():
    psi = _basis()
    with pytest.raises(ParameterError, match="ranking must be one of"):
        hybrid_lars(psi, psi[:, 1], ranking="lars")
    with pytest.raises(ParameterError, match="ranking must be one of"):
        hybrid_lars_outputs(psi, psi[:, 1:3], ranking="omp")
    with pytest.raises(ParameterError, match="fit_pce: ranking must be one of"):
        fit_pce(np.zeros((10, 2)), np.arange(10.0), solver="lars", ranking="LASSO")
