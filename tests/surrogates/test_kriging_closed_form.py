"""Universal Kriging at fixed hyperparameters (spflow.plugins.surrogates.kriging) against direct numpy
implementations of the formulas of docs/surrogates.md (Closed forms at fixed hyperparameters) written out here with
explicit inverses, and against brute-force
leave-one-out refits (Dubrule's formula, with trend re-estimation)."""

import numpy as np
import pytest

from spflow.plugins.surrogates.basis import design_matrix, multi_indices
from spflow.plugins.surrogates.kriging import UniversalKriging, correlation
from spflow.plugins.surrogates.kriging_likelihood import gpy_kernel

NUGGET = 1e-7  # keeps the explicit inverses of the reference accurate


def _data(n=24, seed=0):
    rng = np.random.default_rng(seed)
    z = rng.uniform(-1, 1, (n, 2))
    y = np.c_[np.sin(3 * z[:, 0]) + z[:, 1] ** 2, z[:, 0] * z[:, 1] + 0.1 * np.cos(5 * z[:, 1]), np.exp(z[:, 0])]
    indices = multi_indices(2, 2)  # 1, z1, z2, z1², z1z2, z2² (orthonormal Legendre)
    trend = np.array([[1, 1, 1, 0, 0, 0], [1, 1, 1, 1, 1, 1], [1, 0, 0, 0, 0, 0]], dtype=bool)
    return z, y, design_matrix(z, indices), indices, trend


def _correlation(za, zb, ell):
    """exp(-½ Σ_k (Δ_k/ℓ_k)²), written out (the kernel under test is GPy's RBF)."""
    diff = (za[:, None, :] - zb[None, :, :]) / ell
    return np.exp(-0.5 * np.sum(diff**2, axis=-1))


def _correlation_matern52(za, zb, ell):
    """Matérn 5/2: (1 + √5 d + 5d²/3) exp(−√5 d), d the ℓ-scaled distance."""
    d = np.sqrt(np.sum(((za[:, None, :] - zb[None, :, :]) / ell) ** 2, axis=-1))
    return (1 + np.sqrt(5) * d + 5 * d**2 / 3) * np.exp(-np.sqrt(5) * d)


def _direct_uk(z, y, f, zs, fs, ell, correlation=_correlation):
    """β̂, σ̂², mean and variance at zs of one column by the textbook formulas (explicit inverses)."""
    n = z.shape[0]
    r_mat = correlation(z, z, ell) + NUGGET * np.eye(n)
    r_inv = np.linalg.inv(r_mat)
    a = np.linalg.inv(f.T @ r_inv @ f)
    beta = a @ f.T @ r_inv @ y
    sigma2 = (y - f @ beta) @ r_inv @ (y - f @ beta) / n
    r = correlation(zs, z, ell)
    mean = fs @ beta + r @ r_inv @ (y - f @ beta)
    u = f.T @ r_inv @ r.T - fs.T
    var = sigma2 * (1 - np.einsum("bi,ij,bj->b", r, r_inv, r) + np.einsum("pb,pq,qb->b", u, a, u))
    return beta, sigma2, mean, var


def test_gls_trend_variance_and_prediction_match_the_textbook_formulas():
    z, y, psi, indices, trend = _data()
    ell = np.array([0.6, 0.9])
    uk = UniversalKriging(z, y, psi, trend, "gaussian", ell, NUGGET)
    zs = np.random.default_rng(5).uniform(-1, 1, (15, 2))
    mean, var = uk.predict(zs, design_matrix(zs, indices))
    for j in range(y.shape[1]):
        cols = trend[j]
        beta, sigma2, m_ref, v_ref = _direct_uk(z, y[:, j], psi[:, cols], zs, design_matrix(zs, indices)[:, cols], ell)
        np.testing.assert_allclose(uk.coefficients[cols, j], beta, rtol=1e-6, atol=1e-8)
        assert np.all(uk.coefficients[~cols, j] == 0.0)
        assert uk.process_variance[j] == pytest.approx(sigma2, rel=1e-6)
        np.testing.assert_allclose(mean[:, j], m_ref, rtol=1e-6, atol=1e-8)
        # 1 − rᵀR⁻¹r cancels: the reference's explicit inverse is good to about cond(R)·eps (relative to σ̂²)
        cond = np.linalg.cond(_correlation(z, z, ell) + NUGGET * np.eye(z.shape[0]))
        np.testing.assert_allclose(var[:, j], v_ref, rtol=1e-6, atol=10 * cond * np.finfo(float).eps * sigma2)
    assert (var > 0).all()


def test_dubrule_loo_equals_brute_force_refits_with_trend_reestimation():
    z, y, psi, _, trend = _data(n=20, seed=1)
    ell = np.array([0.7, 0.5])
    uk = UniversalKriging(z, y, psi, trend, "matern52", ell, NUGGET)
    loo = uk.loo_residuals()
    brute = np.empty_like(loo)
    for i in range(z.shape[0]):
        keep = np.arange(z.shape[0]) != i
        for j in range(y.shape[1]):  # refit without point i, same hyperparameters, β̂ re-estimated (direct formulas)
            mean = _direct_uk(z[keep], y[keep, j], psi[keep][:, trend[j]], z[i:i + 1], psi[i:i + 1, trend[j]],
                              ell, _correlation_matern52)[2]
            brute[i, j] = y[i, j] - mean[0]
    np.testing.assert_allclose(loo, brute, rtol=1e-6, atol=1e-9 * np.abs(loo).max())
    # and the relative LOO error of Eq. 3.8
    expected = np.sum(brute**2, axis=0) / np.sum((y - y.mean(axis=0)) ** 2, axis=0)
    np.testing.assert_allclose(uk.relative_loo(), expected, rtol=1e-6)


def test_concentrated_likelihood_value_and_gradient():
    z, y, psi, _, trend = _data(n=18, seed=2)
    ell = np.array([0.5, 0.8])
    n = z.shape[0]
    uk = UniversalKriging(z, y, psi, trend, "gaussian", ell, NUGGET)
    r_mat = _correlation(z, z, ell) + NUGGET * np.eye(n)
    sign, logdet = np.linalg.slogdet(r_mat)
    sigma2 = np.array([_direct_uk(z, y[:, j], psi[:, trend[j]], z[:1], psi[:1, trend[j]], ell)[1] for j in range(3)])
    expected = -np.sum(0.5 * logdet + 0.5 * n * np.log(2 * np.pi * sigma2) + 0.5 * n)  # minus Eq. 3.21, summed
    assert sign > 0 and uk.log_likelihood() == pytest.approx(expected, rel=1e-8)
    # gradient w.r.t. the length scales through dL/dR and GPy's kernel derivatives, against central differences
    kernel = gpy_kernel("gaussian", ell)
    kernel.update_gradients_full(uk.log_likelihood_gradient_k(), z)
    analytic = np.array(kernel.lengthscale.gradient)
    h = 1e-6
    for k in range(2):
        step = np.eye(2)[k] * h
        plus = UniversalKriging(z, y, psi, trend, "gaussian", ell + step, NUGGET).log_likelihood()
        minus = UniversalKriging(z, y, psi, trend, "gaussian", ell - step, NUGGET).log_likelihood()
        assert analytic[k] == pytest.approx((plus - minus) / (2 * h), rel=1e-4)


def test_correlations_equal_gpy_kernels():
    rng = np.random.default_rng(9)
    za, zb = rng.uniform(-1, 1, (7, 3)), rng.uniform(-1, 1, (5, 3))
    ell = np.array([0.3, 1.1, 4.0])
    np.testing.assert_allclose(correlation("gaussian", za, zb, ell), _correlation(za, zb, ell), rtol=1e-12)
    np.testing.assert_allclose(correlation("matern52", za, zb, ell), _correlation_matern52(za, zb, ell), rtol=1e-12)
    for name in ("gaussian", "matern52"):
        np.testing.assert_allclose(correlation(name, za, zb, ell), gpy_kernel(name, ell).K(za, zb), rtol=1e-12)
        np.testing.assert_allclose(np.diag(correlation(name, za, za, ell)), 1.0, rtol=1e-12)
