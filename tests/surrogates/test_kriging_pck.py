"""PC-Kriging versus the plain GP on analytic functions (thesis §3.8): with a polynomial-plus-small-smooth-term
response the polynomial trend pays off; the ``optimal`` mode's trend is a LOO-chosen prefix of the hybrid-LARS order;
``share="output"`` is the same as fitting every output column alone."""

import numpy as np
from scipy.stats import qmc

from spflow.plugins.surrogates.basis import design_matrix
from spflow.plugins.surrogates.gp_model import GP
from spflow.plugins.surrogates.lars import hybrid_lars
from spflow.plugins.surrogates.outputs import OutputIndex
from spflow.plugins.surrogates.pck_model import PCK

NAMES = ["a", "b"]


def _index(m, variables=None):
    variables = np.array(variables if variables is not None else ["f"] * m)
    return OutputIndex(variables, np.array([""] * m), np.arange(m, dtype=float), {v: "1" for v in set(variables)})


def _lhs(n, seed, lower, upper):
    return qmc.scale(qmc.LatinHypercube(d=2, rng=seed).random(n), lower, upper)


def _relative_error(model, f, lower, upper):
    xt = _lhs(400, 99, lower, upper)
    mean, _ = model.predict(xt)
    return np.mean((mean[:, 0] - f(xt)) ** 2) / np.var(f(xt))


def test_polynomial_trend_beats_plain_gp_on_a_polynomial_plus_small_smooth_term():
    lower, upper = np.array([-1.0, 0.0]), np.array([1.0, 4.0])

    def f(x):
        a, b = x[:, 0], (x[:, 1] - 2.0) / 2.0
        return 2 + 3 * a - 2 * b + 4 * a * b + 1.5 * a**3 - b**2 + 0.1 * np.sin(3 * a + 2 * b)

    for seed in (0, 1):
        x = _lhs(30, seed, lower, upper)
        pck = PCK.fit(NAMES, lower, upper, _index(1), x, f(x)[:, None], degree_max=3, restarts=3, seed=seed)
        gp = GP.fit(NAMES, lower, upper, _index(1), x, f(x)[:, None], restarts=3, seed=seed)
        assert pck.loo[0] < gp.loo[0]
        # the LOO ranking is the real one: PC-Kriging also predicts better on an independent set
        assert _relative_error(pck, f, lower, upper) < _relative_error(gp, f, lower, upper)
        assert pck.trend.sum() > 1 and gp.trend.sum() == 1


def test_optimal_mode_keeps_a_loo_chosen_prefix_of_the_lars_order():
    lower, upper = -np.ones(2), np.ones(2)

    def f(x):
        # a polynomial trend plus a part no low-degree polynomial holds (with the LASSO-ordered hybrid LARS the
        # pure sin*cos + bump of before gave a one-term path: nothing to choose a prefix from)
        return 1 + 2 * x[:, 0] - x[:, 1] + 0.5 * x[:, 0] * x[:, 1] + np.sin(4 * x[:, 0]) * np.cos(3 * x[:, 1])

    x = _lhs(40, 2, lower, upper)
    y = f(x)[:, None]
    seq = PCK.fit(NAMES, lower, upper, _index(1), x, y, degree_max=4, restarts=3, mode="sequential")
    opt = PCK.fit(NAMES, lower, upper, _index(1), x, y, degree_max=4, restarts=3, mode="optimal")
    # the hybrid LARS ranking on the chosen PCE basis, recomputed here
    basis_rows = opt.indices
    full = hybrid_lars(design_matrix(opt.to_unit(x), basis_rows), y[:, 0], prefix_rule="min_loo").active
    chosen = np.flatnonzero(opt.trend[0])
    assert set(chosen) == set(full[: chosen.size])
    assert set(np.flatnonzero(seq.trend[0])) == set(full)
    # here a shorter trend wins: smaller Kriging LOO than the sequential (full) trend
    assert chosen.size < full.size and opt.loo[0] < seq.loo[0]


def test_output_sharing_rules():
    lower, upper = -np.ones(2), np.ones(2)
    x = _lhs(20, 3, lower, upper)
    y = np.c_[np.sin(2 * x[:, 0]) + x[:, 1], np.cos(x[:, 0] * x[:, 1]), x[:, 0] ** 2 - np.sin(3 * x[:, 1])]
    outputs = _index(3, ["u", "u", "v"])
    separate = GP.fit(NAMES, lower, upper, outputs, x, y, restarts=1, share="output")
    shared = GP.fit(NAMES, lower, upper, outputs, x, y, restarts=1, share="variable")
    assert separate.lengthscale.shape == (3, 2) and list(separate.group) == [0, 1, 2]
    assert shared.lengthscale.shape == (2, 2) and list(shared.group) == [0, 0, 1]
    # one group per column = each column fitted on its own (restarts=1: deterministic start at ℓ = 1)
    for j in range(3):
        alone = GP.fit(NAMES, lower, upper, _index(1), x, y[:, [j]], restarts=1)
        np.testing.assert_allclose(separate.lengthscale[j], alone.lengthscale[0], rtol=1e-6)
        xt = _lhs(50, 4, lower, upper)
        np.testing.assert_allclose(separate.predict(xt)[0][:, j], alone.predict(xt)[0][:, 0], rtol=1e-6, atol=1e-9)
    # the variable "v" has one column: sharing changes nothing for it
    np.testing.assert_allclose(shared.lengthscale[1], separate.lengthscale[2], rtol=1e-6)
