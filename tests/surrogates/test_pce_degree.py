"""The degree/q-norm loop (UQLab rules; thesis Algorithm 2 lines 6-8): the selected basis minimises ε^mean over the
scored bases, target accuracy and early stop end the loop, vector outputs share one basis."""

import numpy as np
import pytest
from joblib import Parallel

from spflow.core.errors import ParameterError
from spflow.plugins.surrogates.basis import design_matrix, multi_indices
from spflow.plugins.surrogates.degree_adaptive import fit_pce
from spflow.plugins.surrogates.regression import ols


def _data(n=80, seed=0):
    z = np.random.default_rng(seed).uniform(-1, 1, (n, 3))
    y = np.column_stack([np.exp(z[:, 0]) * z[:, 1], np.sin(2 * z[:, 2]) + z[:, 0] ** 2, np.cos(z.sum(axis=1))])
    return z, y


def test_selection_is_the_smallest_mean_modified_loo_and_equals_an_ols_refit():
    z, y = _data()
    fit = fit_pce(z, y, degree_max=6, q=[0.6, 0.8, 1.0], solver="ols", early_stop=False)
    scores = [h[3] for h in fit.history]
    assert fit.modified_loo_mean == pytest.approx(min(scores))
    degree, q, size, _ = fit.history[int(np.argmin(scores))]
    assert (fit.degree, fit.q, fit.indices.shape[0]) == (degree, q, size)
    np.testing.assert_array_equal(fit.indices, multi_indices(3, degree, q))
    ref = ols(design_matrix(z, fit.indices), y)
    np.testing.assert_allclose(fit.coefficients, ref.coefficients.T, rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(fit.loo, ref.loo, rtol=1e-10)
    np.testing.assert_allclose(fit.output_variance, y.var(axis=0))
    assert fit.loo_mean == pytest.approx(np.mean(ref.loo))  # Eq. 3.9
    assert fit.empirical_mean == pytest.approx(np.mean(ref.empirical))  # Eq. 3.10


def test_target_accuracy_stops_at_the_exact_degree():
    z, _ = _data()
    y = 1 + z[:, 0] * z[:, 1] - 2 * z[:, 2] ** 2
    fit = fit_pce(z, y, degree_max=6, q=1.0, target_loo=1e-20)
    assert fit.degree == 2 and [h[0] for h in fit.history] == [1, 2]


def test_early_stop_after_two_degrees_without_improvement():
    z, _ = _data(n=200)
    y = np.random.default_rng(1).normal(size=200)  # pure noise: every degree beyond 1 is worse
    fit = fit_pce(z, y, degree_max=8, q=1.0)
    scores = [h[3] for h in fit.history]
    assert [h[0] for h in fit.history] == [1, 2, 3] and scores[1] > scores[0] and scores[2] > scores[0]
    assert fit.degree == 1


def test_q_values_with_the_same_basis_are_skipped():
    z = np.random.default_rng(2).uniform(-1, 1, (30, 1))
    fit = fit_pce(z, np.sin(3 * z[:, 0]), degree_max=3, q=[0.5, 0.7, 1.0], early_stop=False)
    assert [h[:2] for h in fit.history] == [(1, 0.5), (2, 0.5), (3, 0.5)]


def test_ols_skips_bases_with_more_terms_than_points():
    z, y = _data(n=30)
    fit = fit_pce(z, y, degree_max=4, q=1.0, early_stop=False)  # 35 terms at p = 4
    assert np.isinf(fit.history[-1][3]) and fit.degree < 4


def test_parallel_lars_equals_serial():
    z, y = _data()
    serial = fit_pce(z, y, degree_max=4, solver="lars")
    parallel = fit_pce(z, y, degree_max=4, solver="lars", parallel=Parallel(n_jobs=2, backend="threading"))
    np.testing.assert_array_equal(serial.coefficients, parallel.coefficients)
    assert serial.history == parallel.history


def test_bad_input():
    z, y = _data()
    with pytest.raises(ParameterError, match="degree_max"):
        fit_pce(z, y, degree_max=21)
    with pytest.raises(ParameterError, match="q-norm"):
        fit_pce(z, y, q=[0.5, 1.5])
    with pytest.raises(ParameterError, match="solver"):
        fit_pce(z, y, solver="omp")
    with pytest.raises(ParameterError, match="same N"):
        fit_pce(z[:-1], y)
    with pytest.raises(ParameterError, match="unit box"):
        fit_pce(z * 3, y)
    d = z.shape[1]
    with pytest.raises(ParameterError, match=rf"N = {d + 1} <= d \+ 1 = {d + 1} leaves no leave-one-out error"):
        fit_pce(z[: d + 1], y[: d + 1], solver="ols")
