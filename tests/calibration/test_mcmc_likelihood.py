"""The log posterior of ``PosteriorModel`` (thesis Eqs. 4.2-4.5) against a row-by-row reference written out here:
f(θ) = Aθ + b and the surrogate variance computed directly from the toy's formulas (not through ``predict``), the
observations picked by label, per block the Gaussian log density from ``scipy.stats.norm`` (known or sampled σ), the
Jeffreys marginal from the explicit closed form (v ≡ 0) or from the validated ``jeffreys.log_marginal`` (v > 0; it is
checked against ``scipy.integrate.quad`` in ``test_mcmc_jeffreys.py``). Tolerance 1e-12 relative: the hot path only
rearranges the same arithmetic (validation once at construction, column slices instead of copies, the closed form for
rows whose variance is identically zero)."""

import numpy as np
import pytest
from scipy import stats
from scipy.special import gammaln
from test_mcmc_toys import LinearToy, observations_for, outputs_for
from test_mcmc_toys import toy_kind_registered  # noqa: F401  (autouse fixture: registers the toy surrogate kind)

from spflow.core.errors import ParameterError
from spflow.plugins.calibration import jeffreys
from spflow.plugins.calibration.aligned_data import align
from spflow.plugins.calibration.likelihood import PosteriorModel

NAMES = ["p", "q", "s"]
PAIRS = [("dp", "BCF1"), ("oil_cut", "BCF1")]
LOWER, UPPER = np.array([-1.0, -2.0, 0.0]), np.array([1.0, 2.0, 3.0])


class SwitchedVarianceToy(LinearToy):
    """Variance ``var`` where θ_0 > 0 and identically zero elsewhere, minus a round-off-sized negative part on the
    first output (which the likelihood must clip to 0), so that one batch mixes quadrature and closed-form rows."""

    def variance(self, x):
        v = np.where(x[:, :1] > 0, self.var, 0.0)
        v[:, 0] -= 1e-300
        return v

    def _predict(self, x):
        return x @ self.a.T + self.b, self.variance(x)


def _setup(rng, drop=None):
    """A toy with 7 dp and 6 oil-cut points; ``drop`` removes one observation (non-consecutive block columns)."""
    index = outputs_for({PAIRS[0]: 7, PAIRS[1]: 6})
    a, b = rng.normal(size=(13, 3)), rng.normal(size=13)
    var = rng.uniform(0.05, 0.5, size=13)
    y = a @ np.array([0.2, -0.5, 1.2]) + b + rng.normal(size=13) * 0.4
    if drop is not None:
        y[drop] = np.nan
    toy = SwitchedVarianceToy(NAMES, LOWER - 0.5, UPPER + 0.5, index, a, b, var)
    return toy, align(index, observations_for(index, y), PAIRS), y


def _reference(toy, y, x, noise, sigma=(), surrogate_variance=True):
    """(log posterior, log likelihood) of each row of ``x``, one row and one block at a time."""
    index = toy.outputs
    post, lik = np.full(len(x), -np.inf), np.full(len(x), -np.inf)
    log_prior = -np.sum(np.log(UPPER - LOWER))
    for row, xi in enumerate(x):
        theta = xi[:3]
        if np.any(theta < LOWER) or np.any(theta > UPPER):
            continue
        f = toy.a @ theta + toy.b
        v_all = np.maximum(toy.variance(theta[None])[0], 0.0) if surrogate_variance else np.zeros(13)
        total_lik, total_prior = 0.0, log_prior
        for i, (variable, _) in enumerate(PAIRS):
            cols = [k for k in range(13) if index.variable[k] == variable and np.isfinite(y[k])]
            r, v = y[cols] - f[cols], v_all[cols]
            if noise == "jeffreys_marginal":
                if v.any():
                    total_lik += jeffreys.log_marginal(r[None], v[None])[0]
                else:  # ½ Γ(n/2) π^(-n/2) S^(-n/2)
                    n = len(cols)
                    total_lik += gammaln(n / 2) - np.log(2) - n / 2 * np.log(np.pi * np.sum(r * r))
                continue
            s = sigma[i] if noise == "known" else np.exp(xi[3 + i])
            total_lik += np.sum(stats.norm.logpdf(r, scale=np.sqrt(s * s + v)))
            if noise == "jeffreys_sampled":  # p(log σ) = σ² sqrt(mean_k (σ² + v_k)^-2)
                total_prior += np.log(s * s * np.sqrt(np.mean((s * s + v) ** -2.0)))
        lik[row], post[row] = total_lik, total_lik + total_prior
    return post, lik


def _points(rng, count, extra=0):
    """Rows in a box 10 % wider than the prior (some outside it), θ_0 of both signs; ``extra`` log σ columns."""
    width = UPPER - LOWER
    theta = rng.uniform(LOWER - 0.1 * width, UPPER + 0.1 * width, size=(count, 3))
    return np.column_stack([theta, rng.normal(-0.5, 0.5, size=(count, extra))])


CASES = [("jeffreys_marginal", True), ("jeffreys_marginal", False), ("known", True), ("known", False),
         ("jeffreys_sampled", True), ("jeffreys_sampled", False)]


@pytest.mark.parametrize("drop", [None, 3], ids=["consecutive-columns", "gap-in-columns"])
@pytest.mark.parametrize("noise, surrogate_variance", CASES, ids=[f"{n}-{v}" for n, v in CASES])
def test_log_posterior_equals_the_row_by_row_reference(noise, surrogate_variance, drop):
    rng = np.random.default_rng([CASES.index((noise, surrogate_variance)), drop or 0])
    toy, aligned, y = _setup(rng, drop)
    sigma = (0.5, 0.3) if noise == "known" else ()
    model = PosteriorModel(toy, aligned, PAIRS, LOWER, UPPER, noise=noise, sigma=sigma,
                           surrogate_variance=surrogate_variance)
    x = _points(rng, 40, model.ndim - 3)
    post, lik = model.evaluate(x)
    ref_post, ref_lik = _reference(toy, y, x, noise, sigma, surrogate_variance)
    inside = np.isfinite(ref_post)
    assert 5 < inside.sum() < 40 and (x[inside, 0] > 0).any() and (x[inside, 0] <= 0).any()
    np.testing.assert_array_equal(np.isfinite(post), inside)
    np.testing.assert_allclose(post[inside], ref_post[inside], rtol=1e-12, atol=0)
    np.testing.assert_allclose(lik[inside], ref_lik[inside], rtol=1e-12, atol=0)
    # one row at a time (an MH chain's call) gives the batch's numbers
    single = np.array([model.evaluate(row[None])[0][0] for row in x])
    np.testing.assert_allclose(single[inside], post[inside], rtol=1e-12, atol=0)
    assert np.all(single[~inside] == -np.inf)


def test_unchecked_marginal_equals_the_validated_one():
    rng = np.random.default_rng(8)
    r = rng.normal(size=(6, 20))
    v = rng.uniform(0.0, 0.3, size=(6, 20))
    v[[1, 4]] = 0.0  # closed-form rows among quadrature rows
    np.testing.assert_array_equal(jeffreys.log_marginal_checked(r, v), jeffreys.log_marginal(r, v))
    np.testing.assert_array_equal(jeffreys.log_marginal_checked(r, None), jeffreys.log_marginal(r, 0.0))
    np.testing.assert_array_equal(jeffreys.log_marginal_checked(r[:2], v[:2] + 0.1),
                                  jeffreys.log_marginal(r[:2], v[:2] + 0.1))


def test_bad_model_input_is_named_at_construction():
    rng = np.random.default_rng(9)
    toy, aligned, _ = _setup(rng)
    with pytest.raises(ParameterError, match="lower and upper"):
        PosteriorModel(toy, aligned, PAIRS, LOWER[:2], UPPER[:2])
    with pytest.raises(ParameterError, match="noise must be one of"):
        PosteriorModel(toy, aligned, PAIRS, LOWER, UPPER, noise="student")
    with pytest.raises(ParameterError, match="sigma"):
        PosteriorModel(toy, aligned, PAIRS, LOWER, UPPER, noise="known", sigma=(0.5,))
