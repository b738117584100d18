"""Out-of-sample scores: the sequential pointwise terms sum to the Gaussian log density (scipy reference), the
measurement SE reduces to ||w_k - w_ref|| without parameter uncertainty, the pointwise SE is loo_compare's."""

import numpy as np
import pytest
from scipy.stats import multivariate_normal

from spflow.plugins.gap.predictive_scores import Predictive, _terms, compare


def test_terms_sum_to_the_multivariate_normal_log_density():
    rng = np.random.default_rng(0)
    n, q = 25, 3
    w, a = rng.normal(size=n), rng.normal(size=(n, q))
    cov = np.diag([0.3, 0.1, 0.05])
    terms = _terms(w, a, cov)
    S = np.eye(n) + a @ cov @ a.T
    expected = multivariate_normal(np.zeros(n), S).logpdf(w) + 0.5 * n * np.log(2 * np.pi)
    assert terms.total == pytest.approx(expected, rel=1e-10)
    np.testing.assert_allclose(terms.gradient, np.linalg.solve(S, w), rtol=1e-10)


def test_compare_without_parameter_uncertainty():
    rng = np.random.default_rng(1)
    w0, w1 = rng.normal(size=40) * 3, rng.normal(size=40)
    ref, model = (_terms(w, np.zeros((40, 1)), np.zeros((1, 1))) for w in (w0, w1))
    delta, se, se_pointwise = compare(model, ref)
    d = -0.5 * (w1**2 - w0**2)
    assert delta == pytest.approx(d.sum())
    assert se == pytest.approx(np.linalg.norm(w1 - w0))
    assert se_pointwise == pytest.approx(np.sqrt(40 * d.var(ddof=1)))
    nan = Predictive(np.full(3, np.nan), np.zeros(3), np.zeros(3))
    assert np.isnan(compare(nan, nan)[0])
