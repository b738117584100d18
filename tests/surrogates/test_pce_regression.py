"""OLS with hat-matrix error estimates (thesis Eqs. 3.6-3.8, modified LOO of Blatman 2009) against brute-force
leave-one-out refits and direct formulas."""

import numpy as np
import pytest

from spflow.core.errors import ParameterError
from spflow.plugins.surrogates.basis import design_matrix, multi_indices
from spflow.plugins.surrogates.regression import ols


def _problem(n=40, d=3, p=3, m=4, seed=0):
    rng = np.random.default_rng(seed)
    z = rng.uniform(-1, 1, (n, d))
    psi = design_matrix(z, multi_indices(d, p, 1.0))
    y = np.column_stack([np.exp(z[:, 0] * (k + 1) / 3) + np.sin(2 * z[:, 1]) * z[:, 2] + 0.05 * rng.normal(size=n)
                         for k in range(m)])
    return psi, y


def test_loo_equals_brute_force_refits():
    psi, y = _problem()
    n = psi.shape[0]
    loo_residuals = np.empty_like(y)
    for i in range(n):
        keep = np.arange(n) != i
        coef, *_ = np.linalg.lstsq(psi[keep], y[keep], rcond=None)
        loo_residuals[i] = y[i] - psi[i] @ coef
    expected = np.mean(loo_residuals**2, axis=0) / y.var(axis=0)
    fit = ols(psi, y)
    np.testing.assert_allclose(fit.loo, expected, rtol=1e-9)


def test_coefficients_empirical_and_modified_loo_formulas():
    psi, y = _problem(seed=1)
    n, p = psi.shape
    coef, *_ = np.linalg.lstsq(psi, y, rcond=None)
    fit = ols(psi, y)
    np.testing.assert_allclose(fit.coefficients, coef, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(fit.empirical, np.mean((y - psi @ coef) ** 2, axis=0) / y.var(axis=0), rtol=1e-9)
    t = n / (n - p) * (1 + np.trace(np.linalg.inv(psi.T @ psi)))
    np.testing.assert_allclose(fit.modified_loo, t * fit.loo, rtol=1e-9)
    assert np.all(fit.modified_loo > fit.loo)
    np.testing.assert_allclose(fit.leverage, np.diag(psi @ np.linalg.inv(psi.T @ psi) @ psi.T), atol=1e-12)


def test_single_output_shapes():
    psi, y = _problem(m=1)
    fit = ols(psi, y[:, 0])
    assert fit.coefficients.shape == (psi.shape[1],) and np.ndim(fit.loo) == 0


def test_underdetermined_gives_infinite_modified_loo_and_constant_output_zero_error():
    psi, y = _problem(n=15, p=3)  # 20 terms > 15 points
    y[:, 1] = 2.5
    fit = ols(psi, y)
    assert np.isinf(fit.modified_loo[0])
    assert fit.loo[1] == 0.0 and fit.modified_loo[1] == 0.0 and fit.empirical[1] == 0.0


def test_rank_deficient_falls_back_to_pseudo_inverse():
    psi, y = _problem()
    psi = np.column_stack([psi, psi[:, 3]])  # repeated regressor
    fit = ols(psi, y)
    assert fit.rank == psi.shape[1] - 1
    np.testing.assert_allclose(fit.coefficients, np.linalg.pinv(psi) @ y, rtol=1e-8, atol=1e-10)


def test_bad_input():
    psi, y = _problem()
    with pytest.raises(ParameterError, match="same N"):
        ols(psi, y[:-1])
    with pytest.raises(ParameterError, match="finite"):
        ols(psi, np.where(y > 0.5, np.nan, y))
