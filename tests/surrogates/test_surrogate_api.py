"""The plain library API (``spflow.surrogates``: ``PCE``, ``GP``, ``PCK``) against independent references: Ishigami's
closed-form Sobol indices, a quadratic on a physical box, analytic Legendre-coefficient indices of a polynomial, the
data at the training points; shapes shaped like y; bad input named before any work; one default everywhere."""

import inspect

import numpy as np
import pytest
from scipy.special import eval_legendre
from scipy.stats import qmc
from sklearn.base import clone

from spflow.core.errors import ParameterError
from spflow.plugins.surrogates import kriging, pck_model
from spflow.plugins.surrogates.degree_adaptive import fit_pce
from spflow.plugins.surrogates.gp_model import GP as GPModel
from spflow.plugins.surrogates.kriging_stage import GPStage, PCKStage
from spflow.plugins.surrogates.outputs import OutputIndex
from spflow.plugins.surrogates.pce_stage import PCEStage
from spflow.plugins.surrogates.pck_model import PCK as PCKModel
from spflow.surrogates import GP, PCE, PCK

BOX = [(100.0, 200.0), (0.01, 0.02)]


def _lhs(n, bounds, seed):
    lower, upper = np.array(bounds, dtype=float).T
    return qmc.scale(qmc.LatinHypercube(d=len(bounds), rng=seed).random(n), lower, upper)


def _quadratic(x):
    return 3.0 + 0.02 * x[:, 0] ** 2 - 5.0e4 * x[:, 1] ** 2 + 40.0 * x[:, 0] * x[:, 1] - 0.5 * x[:, 0]


def test_ishigami_first_and_total_indices_from_the_pce_api_at_n400():
    a, b = 7.0, 0.1  # Ishigami (1990); X ~ U[-π, π]^3. Partial variances (Sobol' & Levitan 1999):
    d1 = 0.5 * (1.0 + b * np.pi**4 / 5.0) ** 2
    d2 = a**2 / 8.0
    d13 = b**2 * np.pi**8 * (1.0 / 18.0 - 1.0 / 50.0)
    variance = a**2 / 8.0 + b * np.pi**4 / 5.0 + b**2 * np.pi**8 / 18.0 + 0.5
    assert abs(d1 + d2 + d13 - variance) < 1e-12  # the decomposition adds up
    first = np.array([d1, d2, 0.0]) / variance
    total = np.array([d1 + d13, d2, d13]) / variance

    x = _lhs(400, [(-np.pi, np.pi)] * 3, seed=0)
    y = np.sin(x[:, 0]) + a * np.sin(x[:, 1]) ** 2 + b * x[:, 2] ** 4 * np.sin(x[:, 0])
    indices = PCE(bounds=[(-np.pi, np.pi)] * 3).fit(x, y).sobol_indices()  # the defaults
    assert indices.first.shape == indices.total.shape == (3,)
    np.testing.assert_allclose(indices.first, first, atol=2e-3)
    np.testing.assert_allclose(indices.total, total, atol=2e-3)


def test_a_quadratic_is_recovered_exactly_on_a_physical_box():
    x = _lhs(20, BOX, seed=3)
    model = PCE(bounds=BOX).fit(x, _quadratic(x))
    xt = _lhs(200, BOX, seed=4)
    truth = _quadratic(xt)
    np.testing.assert_allclose(model.predict(xt), truth, rtol=1e-10, atol=1e-10 * np.abs(truth).max())
    assert model.loo_error_ < 1e-16  # an exact fit: a float for a scalar y
    # the box's corners are inside the bounds and predicted too
    corners = np.array([[100.0, 0.01], [200.0, 0.02], [100.0, 0.02], [200.0, 0.01]])
    np.testing.assert_allclose(model.predict(corners), _quadratic(corners), rtol=1e-10)


@pytest.mark.parametrize("estimator", [PCE(BOX), GP(BOX, restarts=1), PCK(BOX, degree_max=2, restarts=1)],
                         ids=["pce", "gp", "pck"])
def test_predictions_are_shaped_like_y(estimator):
    x, xt = _lhs(25, BOX, seed=5), _lhs(7, BOX, seed=6)
    f = _quadratic(x) + 30.0 * np.sin(200.0 * x[:, 1])
    for y, shape in ((f, (7,)), (f[:, None], (7, 1)), (np.column_stack([f, 2.0 * f + 1.0, np.cos(x[:, 0])]), (7, 3))):
        model = clone(estimator).fit(x, y)
        mean = model.predict(xt)
        mean_std, std = model.predict(xt, return_std=True)
        assert mean.shape == mean_std.shape == std.shape == shape
        np.testing.assert_array_equal(mean, mean_std)  # the mean does not depend on whether the variance is asked
        assert (std >= 0).all()
        assert np.shape(model.loo_error_) == shape[1:]
    if isinstance(estimator, PCE):  # the PCE's std is its constant corrected-LOO error estimate
        error = np.sqrt(model.model_.modified_loo * np.var(y, axis=0))
        np.testing.assert_allclose(std, np.broadcast_to(error, std.shape))


def test_gp_predicts_the_data_at_the_training_points_and_is_uncertain_between_them():
    lower, upper = np.array(BOX).T

    def f(x):
        u = (x - lower) / (upper - lower)
        return np.column_stack([np.sin(2 * np.pi * u[:, 0]) * np.cos(np.pi * u[:, 1]) + u[:, 0],
                                np.exp(u[:, 1]) * np.cos(3 * u[:, 0])])

    x = _lhs(25, BOX, seed=7)
    y = f(x)
    model = GP(BOX, restarts=2).fit(x, y)
    mean, std = model.predict(x, return_std=True)
    spread = y.max(axis=0) - y.min(axis=0)
    assert (np.abs(mean - y) < 1e-3 * spread).all()  # interpolates (up to the nugget)
    far = model.predict(_lhs(200, BOX, seed=8), return_std=True)[1]
    assert (std.max(axis=0) < 0.1 * far.max(axis=0)).all()


def test_kriging_computes_the_variance_only_when_asked(monkeypatch):
    x = _lhs(15, BOX, seed=9)
    model = GP(BOX, restarts=1).fit(x, _quadratic(x))
    asked = []
    original = kriging.UniversalKriging.predict

    def spy(self, z, basis, variance=True):
        asked.append(variance)
        return original(self, z, basis, variance)

    monkeypatch.setattr(kriging.UniversalKriging, "predict", spy)
    model.predict(x[:3])
    model.predict(x[:3], return_std=True)
    assert asked == [False, True]


def _legendre(z, n):
    return np.sqrt(2 * n + 1) * eval_legendre(n, z)  # orthonormal under U[-1, 1]


def test_pck_trend_indices_equal_the_pce_indices_and_the_analytic_ones_on_a_polynomial():
    bounds = [(0.0, 4.0), (-2.0, 2.0), (10.0, 30.0)]
    lower, upper = np.array(bounds).T
    # f = Σ c_α Ψ_α written in the orthonormal Legendre basis, so its partial variances are the c_α² (Sudret 2008)
    terms = {(1, 0, 0): 2.0, (0, 2, 0): -1.5, (0, 0, 1): 0.7, (1, 1, 0): 1.2, (2, 0, 1): 0.4, (0, 3, 0): 0.3}

    def f(x):
        z = 2.0 * (x - lower) / (upper - lower) - 1.0
        return 5.0 + sum(c * np.prod([_legendre(z[:, k], n) for k, n in enumerate(a)], axis=0)
                         for a, c in terms.items())

    variance = sum(c**2 for c in terms.values())
    first = np.array([sum(c**2 for a, c in terms.items() if a[k] > 0 and sum(a) == a[k]) for k in range(3)]) / variance
    total = np.array([sum(c**2 for a, c in terms.items() if a[k] > 0) for k in range(3)]) / variance

    x = _lhs(60, bounds, seed=10)
    pce = PCE(bounds).fit(x, f(x)).sobol_indices()
    # q = 0.9 needs p = 4 for (2, 0, 1)
    pck = PCK(bounds, degree_max=4, restarts=1).fit(x, f(x)).sobol_indices(part="trend")
    for indices in (pce, pck):
        np.testing.assert_allclose(indices.first, first, atol=1e-8)
        np.testing.assert_allclose(indices.total, total, atol=1e-8)
    np.testing.assert_allclose(pck.first, pce.first, atol=1e-8)
    np.testing.assert_allclose(pck.total, pce.total, atol=1e-8)


def test_share_variable_shares_or_refuses(monkeypatch):
    x = _lhs(20, BOX, seed=11)
    y = np.column_stack([_quadratic(x), np.sin(300.0 * x[:, 1])])
    shared = GP(BOX, share="variable", restarts=1).fit(x, y)
    assert shared.model_.lengthscale.shape == (1, 2) and list(shared.model_.group) == [0, 0]
    separate = GP(BOX, share="output", restarts=1).fit(x, y)
    assert separate.model_.lengthscale.shape == (2, 2)
    # outputs that each carry their own label: nothing to share -> a clear error, not one model per output
    labelled = OutputIndex(np.array(["a", "b"]), np.array(["", ""]), np.array([np.nan, np.nan]), {"a": "1", "b": "1"})
    lower, upper = np.array(BOX).T

    def no_work(*args, **kwargs):
        raise AssertionError("PCK fitted its trend before refusing the options")

    monkeypatch.setattr(pck_model, "fit_pce", no_work)
    for cls in (GPModel, PCKModel):
        with pytest.raises(ParameterError, match="each of the 2 outputs has its own label.*share='output'"):
            cls.fit(["p", "q"], lower, upper, labelled, x, y, share="variable", restarts=1)


@pytest.mark.parametrize("call, message", [
    (lambda: PCE([(1.0, 0.0)]).fit([[0.5]], [1.0]), r"bounds\[0\] = \[1, 0\] must be finite with lower < upper"),
    (lambda: PCE([1.0, 2.0]).fit([[1.5]], [1.0]), r"bounds must have shape \(d, 2\)"),
    (lambda: PCE(BOX).fit(np.ones((5, 3)), np.ones(5)), r"X must have shape \(n, 2\).*got shape \(5, 3\)"),
    (lambda: PCE(BOX).fit([[150.0, 0.03]] * 5, np.ones(5)),
     r"X\[0, 1\] = 0.03 lies outside bounds\[1\] = \[0.01, 0.02\]"),
    (lambda: PCE(BOX).fit([[150.0, np.nan]] * 5, np.ones(5)), r"X\[0, 1\] = nan; X must be finite"),
    (lambda: PCE(BOX).fit([[150.0, 0.015]] * 5, np.ones(4)), r"y must have shape \(n,\) or \(n, m\) with n = 5"),
    (lambda: PCE(BOX).fit([[150.0, 0.015]] * 5, [1.0, 2.0, np.inf, 0.0, 1.0]), r"y\[2\] = inf; y must be finite"),
    (lambda: PCE(BOX, names=["a"]).fit([[150.0, 0.015]] * 5, np.ones(5)), r"names must be 2 distinct input names"),
    (lambda: GP(BOX, n_jobs=0).fit([[150.0, 0.015]] * 5, np.ones(5)), r"n_jobs must be a non-zero integer"),
    (lambda: GP(BOX).predict([[150.0, 0.015]]), r"GP is not fitted yet"),
])
def test_bad_input_names_the_argument_and_the_allowed_range(call, message):
    with pytest.raises(ParameterError, match=message):
        call()


def test_predict_refuses_points_outside_the_box():
    x = _lhs(20, BOX, seed=12)
    model = PCE(BOX).fit(x, _quadratic(x))
    with pytest.raises(ParameterError, match=r"X\[1, 0\] = 250 lies outside bounds\[0\] = \[100, 200\]"):
        model.predict([[150.0, 0.015], [250.0, 0.015]])
    with pytest.raises(ParameterError, match=r"X must have shape \(n, 2\)"):
        model.predict([150.0, 0.015])


def _defaults(function):
    return {k: p.default for k, p in inspect.signature(function).parameters.items()
            if p.default is not inspect.Parameter.empty}


def test_one_default_everywhere():
    """The API, the fit functions and the stages share every default; restarts is 3 as docs/surrogates.md says."""
    for api, function, stage in ((PCE, fit_pce, PCEStage), (GP, GPModel.fit, GPStage), (PCK, PCKModel.fit, PCKStage)):
        mine, theirs = _defaults(api.__init__), _defaults(function)
        shared = set(mine) & set(theirs) - {"names"}
        assert shared, api
        assert {k: mine[k] for k in shared} == {k: theirs[k] for k in shared}, api
        for k in shared & set(stage.params):
            assert stage.params[k].default == mine[k], (api, k)
    assert _defaults(GP.__init__)["restarts"] == _defaults(PCK.__init__)["restarts"] == 3
