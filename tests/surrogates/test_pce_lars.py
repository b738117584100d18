"""Hybrid LARS (Blatman & Sudret 2011): exact support recovery of sparse polynomials, OLS refits and modified LOO
along the path equal to independent recomputation, one LARS per output column."""

import numpy as np
import pytest

from spflow.core.errors import ParameterError
from spflow.plugins.surrogates.basis import design_matrix, multi_indices
from spflow.plugins.surrogates.degree_adaptive import fit_pce
from spflow.plugins.surrogates.folds import FOLD_SEED
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
    result = hybrid_lars(psi, y, prefix_rule="min_loo")
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


def _kinked_problem(seed):
    """60 points in 3-D, the full degree-4 basis (35 terms), a kinked response with noise: the LARS path runs to its
    end and its nested models are scored from a constant to 35 terms."""
    z = np.random.default_rng(seed).uniform(-1, 1, (60, 3))
    psi = design_matrix(z, multi_indices(3, 4, 1.0))
    y = np.abs(z[:, 0]) + np.exp(z[:, 1]) * z[:, 2] + 0.05 * np.random.default_rng(100 + seed).normal(size=60)
    return psi, y


@pytest.mark.parametrize("seed", [1, 5, 9])
def test_one_standard_error_rule_by_hand_along_the_least_angle_ranking(seed):
    """The one-SE rule recomputed from its definition (Hastie, Tibshirani & Friedman 2009, §7.10): every nested model
    of the plain-LAR order (the order written out in ``_lar_entry_order``) refitted by OLS, its LOO residuals by
    N explicit refits without each point, T(P, N) from (ΨᵀΨ)⁻¹; the smallest model whose corrected LOO is within one
    standard error (T times sd(e²)/√N of the minimising model's N squared LOO residuals) of the minimum."""
    psi, y = _kinked_problem(seed)
    n = y.size
    x = psi[:, 1:] - psi[:, 1:].mean(axis=0)
    x /= np.linalg.norm(x, axis=0)
    order = [0, *(1 + np.array(_lar_entry_order(x, y - y.mean(), x.shape[1])))]
    scores, errors = [], []
    for k in range(1, len(order) + 1):
        a = psi[:, order[:k]]
        loo = np.array([y[i] - a[i] @ np.linalg.lstsq(np.delete(a, i, 0), np.delete(y, i), rcond=None)[0]
                        for i in range(n)])
        squared = loo**2 / y.var()
        t = n / (n - k) * (1.0 + np.trace(np.linalg.inv(a.T @ a)))
        scores.append(t * squared.mean())
        errors.append(t * squared.std(ddof=1) / np.sqrt(n))
    best = int(np.argmin(scores))
    one_se = int(np.flatnonzero(np.array(scores) <= scores[best] + errors[best])[0])
    assert one_se < best  # on these designs the rule keeps fewer terms than the minimum
    result = hybrid_lars(psi, y, ranking="lar", prefix_rule="one_se")
    np.testing.assert_array_equal(result.active, order[: one_se + 1])
    np.testing.assert_allclose(result.modified_loo, scores[one_se], rtol=1e-8)
    refit = np.linalg.lstsq(psi[:, order[: one_se + 1]], y, rcond=None)[0]
    np.testing.assert_allclose(result.coefficients[result.active], refit, rtol=1e-8, atol=1e-12)
    assert hybrid_lars(psi, y, ranking="lar", prefix_rule="min_loo").active.size == best + 1  # the other rule


def _ten_fold_error(psi, y, ranking):
    """Textbook 10-fold cross-validation of the LARS step with the one-SE rule: the documented folds (a permutation
    from default_rng(FOLD_SEED) cut into 10 near-equal consecutive parts), a fit on the other nine, the held-out
    squared errors summed."""
    order = np.random.default_rng(FOLD_SEED).permutation(y.size)
    total = 0.0
    for held in np.array_split(order, 10):
        train = np.setdiff1d(np.arange(y.size), held)
        model = hybrid_lars(psi[train], y[train], ranking=ranking, prefix_rule="one_se")
        total += np.sum((psi[held] @ model.coefficients - y[held]) ** 2)
    return total


def test_cross_validated_ranking_is_the_textbook_ten_fold_choice_per_output():
    """ranking="cv" keeps, per output, the ranking with the smaller 10-fold error of the whole LARS step; the designs
    are ones where the two choices differ (LAR on seeds 1 and 9, LASSO on seeds 0 and 4) and give different models."""
    chosen_seen = set()
    for seed in (0, 1, 4, 9):
        psi, y = _kinked_problem(seed)
        errors = {r: _ten_fold_error(psi, y, r) for r in ("lasso", "lar")}
        chosen = min(errors, key=errors.get)
        chosen_seen.add(chosen)
        result = hybrid_lars(psi, y, ranking="cv", prefix_rule="one_se")
        assert result.ranking == chosen
        reference = hybrid_lars(psi, y, ranking=chosen, prefix_rule="one_se")
        np.testing.assert_array_equal(result.active, reference.active)
        np.testing.assert_allclose(result.coefficients, reference.coefficients, rtol=1e-12, atol=1e-14)
    assert chosen_seen == {"lasso", "lar"}
    # vector outputs on one design: one choice per column
    psi, y1 = _kinked_problem(1)
    y2 = np.sin(3.0 * psi[:, 1]) + psi[:, 2] * psi[:, 3]
    expected = [min(("lasso", "lar"), key=lambda r: _ten_fold_error(psi, y, r)) for y in (y1, y2)]
    results = hybrid_lars_outputs(psi, np.column_stack([y1, y2]), ranking="cv", prefix_rule="one_se")
    assert [r.ranking for r in results] == expected == ["lar", "lasso"]


@pytest.mark.filterwarnings("ignore::spflow.core.errors.DegreeCapWarning")
@pytest.mark.parametrize("ranking, prefix_rule", [("cv", "one_se"), ("lasso", "one_se"), ("cv", "min_loo")])
def test_fit_pce_applies_the_selection_options_to_the_basis_the_default_search_selects(ranking, prefix_rule):
    """The degree and q search is the same whatever the options (a basis scored by the smallest corrected LOO along
    the LASSO path); the one-SE rule and the cross-validated ranking replace only the model on the selected basis."""
    z = np.random.default_rng(3).uniform(-1, 1, (80, 3))
    y = np.abs(z[:, 0]) + np.exp(z[:, 1]) * z[:, 2]
    minimum = fit_pce(z, y, solver="lars", degree_max=6, prefix_rule="min_loo")
    chosen = fit_pce(z, y, solver="lars", degree_max=6, ranking=ranking, prefix_rule=prefix_rule)
    assert not np.allclose(chosen.coefficients, minimum.coefficients)  # the options change the model here
    assert (chosen.degree, chosen.q, chosen.history) == (minimum.degree, minimum.q, minimum.history)
    np.testing.assert_array_equal(chosen.indices, minimum.indices)
    on_basis = hybrid_lars(design_matrix(z, minimum.indices), y, ranking=ranking, prefix_rule=prefix_rule)
    np.testing.assert_allclose(chosen.coefficients[0], on_basis.coefficients, rtol=1e-12, atol=1e-14)
    assert chosen.rankings == (on_basis.ranking,) and minimum.rankings == ("lasso",)
    np.testing.assert_allclose(chosen.modified_loo[0], on_basis.modified_loo)


def test_the_default_lars_model_is_the_one_se_model_of_the_lasso_ranking():
    z = np.random.default_rng(3).uniform(-1, 1, (80, 3))
    y = np.abs(z[:, 0]) + np.exp(z[:, 1]) * z[:, 2]
    default = fit_pce(z, y, solver="lars", degree_max=6)
    explicit = fit_pce(z, y, solver="lars", degree_max=6, ranking="lasso", prefix_rule="one_se")
    np.testing.assert_array_equal(default.coefficients, explicit.coefficients)
    psi = design_matrix(z, default.indices)
    np.testing.assert_array_equal(hybrid_lars(psi, y).coefficients,
                                  hybrid_lars(psi, y, ranking="lasso", prefix_rule="one_se").coefficients)


def test_unknown_prefix_rule_is_refused():
    psi = _basis()
    with pytest.raises(ParameterError, match="hybrid_lars: prefix_rule must be one of"):
        hybrid_lars(psi, psi[:, 1], prefix_rule="1se")
    with pytest.raises(ParameterError, match="fit_pce: prefix_rule must be one of"):
        fit_pce(np.zeros((10, 2)), np.arange(10.0), solver="lars", prefix_rule="one-se")
    with pytest.raises(ParameterError, match="ranking 'cv' needs N >= 4"):
        hybrid_lars(psi[:3], psi[:3, 1], ranking="cv")
