"""PSIS-LOO on the linearised posterior against the exact leave-one-out predictive of the linear-Gaussian model."""

import numpy as np
import pytest
from scipy.stats import norm

from spflow.core.errors import ParameterError
from spflow.plugins.gap.least_squares import Fit
from spflow.plugins.gap.psis_loo import compare_loo, psis_loo
from spflow.plugins.gap.quantification import parameter_covariance


def exact_loo(r, jac, tau):
    """log p(w_i = 0 | other points) for w(dz) = r + J dz, the posterior of dz being N(0, C) (module docstring of
    psis_loo): remove point i's likelihood term from the Gaussian posterior and predict it."""
    precision = np.linalg.inv(parameter_covariance(jac, tau))
    out = []
    for i in range(r.size):
        j = jac[i]
        a = precision - np.outer(j, j)
        mean = np.linalg.solve(a, r[i] * j)  # the posterior's linear term is 0; point i contributed -r_i j_i
        out.append(norm.logpdf(0.0, r[i] + j @ mean, np.sqrt(1.0 + j @ np.linalg.solve(a, j))))
    return np.array(out)


def test_psis_loo_matches_exact_leave_one_out():
    rng = np.random.default_rng(3)
    n, q = 50, 3
    jac = rng.normal(size=(n, q)) * 0.8
    jac[:4] = 0.0  # points the parameters do not move: LOO is their log-likelihood, k undefined
    r = rng.normal(size=n)
    r -= jac @ np.linalg.lstsq(jac, r, rcond=None)[0]  # a least-squares optimum: J' r = 0
    fitted = Fit(np.full(q, 0.5), (), q, r, jac, 0, "")
    loo = psis_loo(fitted, tau=0.5, draws=8000, seed=1)
    exact = exact_loo(r, jac, 0.5)
    assert np.all(loo.pareto_k[4:] < 0.7) and np.isnan(loo.pareto_k[:4]).all()
    assert loo.pointwise == pytest.approx(exact, abs=0.02)
    assert loo.elpd == pytest.approx(exact.sum(), abs=0.3)
    assert loo.se == pytest.approx(np.sqrt(n * exact.var()), rel=0.05)
    # a model that fits a localised bump better gains there: dELPD against a closed-form reference
    worse = Fit(fitted.z, (), q, r + np.where(np.arange(n) < 10, 1.5, 0.0), jac, 0, "")
    delta, se = compare_loo(loo, psis_loo(worse, tau=0.5, draws=8000, seed=1))
    reference = exact - exact_loo(worse.residual, jac, 0.5)
    assert delta == pytest.approx(reference.sum(), rel=0.05)
    assert se == pytest.approx(np.sqrt(n * reference.var(ddof=1)), rel=0.05)


def test_psis_loo_rejects_too_few_draws():
    fitted = Fit(np.zeros(1), (), 1, np.zeros(5), np.ones((5, 1)), 0, "")
    with pytest.raises(ParameterError, match="draws >= 100"):
        psis_loo(fitted, draws=10)
