"""Weighted least squares in the unit box on an analytic model (a stand-in predictor with the Predictor
interface): recovery of known parameters and strengths, the Jacobian, failure handling, parameter-set starts."""

import numpy as np
import pytest
import xarray as xr

from spflow.core.errors import ParameterError, SpflowError
from spflow.plugins.design.parameter_map import ParameterMap
from spflow.plugins.gap.base_calibration import calibrate_base, parameter_set_starts
from spflow.plugins.gap.base_model import BaseModel
from spflow.plugins.gap.catalogue import CandidateEffect
from spflow.plugins.gap.error_model import BlockErrorModel
from spflow.plugins.gap.layout import Block, Layout
from spflow.plugins.gap.least_squares import fit

PV = np.linspace(0.0, 4.0, 41)
BASE = BaseModel.from_mapping({"parameters": {"AD31": [0.0, 2.0], "GAMHF": {"range": [10.0, 100.0],
                                                                            "scale": "log"}}})
EFFECT = CandidateEffect("drift", 0.0, 0.0, 1.0, False, (0.05, 1.0), (0.5,))


def model(a, b, c):
    return a * np.exp(-PV * b / 50.0) + c * PV


class AnalyticPredictor:
    """y = AD31 exp(-pv GAMHF / 50) + drift * pv, with the Predictor's predict() signature."""

    def __init__(self, fail=lambda a, b: False):
        self.base, self.fail, self.runs = BASE, fail, 0
        self.distinct: set[tuple] = set()   # the points a memoising predictor would run


    def predict(self, points, experiments, variables=None):
        out = []
        for u, strengths in points:
            a, b = self.base.values(u)
            self.runs += 1
            self.distinct.add((tuple(u), tuple(sorted((strengths or {}).items()))))
            out.append(None if self.fail(a, b) else {"E": {"y": model(a, b, (strengths or {}).get("drift", 0.0))}})
        return out


def layout(observed, sigma=0.01):
    return Layout((Block("y", "E", np.arange(PV.size), PV, observed, np.zeros(PV.size, int),
                         BlockErrorModel(np.full(PV.size, sigma), 0.3)),))


def test_recovers_parameters_and_strength():
    truth = model(1.2, 80.0, 0.3)
    result = fit(AnalyticPredictor(), layout(truth), [np.array([0.5, 0.5, 0.5])], (EFFECT,), max_nfev=200,
                 diff_step=1e-6)
    np.testing.assert_allclose(BASE.values(result.u), [1.2, 80.0], rtol=1e-4)
    assert result.strengths["drift"] == pytest.approx(0.3, rel=1e-4)
    assert result.chi2 < 1e-6
    # the stored Jacobian is d(whitened residual)/d(unit coordinates): analytic derivative, whitened
    a, b = 1.2, 80.0
    dy = np.column_stack([np.exp(-PV * b / 50) * 2.0,                                # dAD31/du = 2
                          -a * PV / 50 * np.exp(-PV * b / 50) * b * np.log(10.0),     # log scale: db/du = b ln 10
                          PV])
    np.testing.assert_allclose(result.jacobian, layout(truth).whiten(dy), rtol=1e-3, atol=1e-3)


def test_best_of_several_starts_and_failed_runs():
    truth = model(0.8, 20.0, 0.0)
    predictor = AnalyticPredictor(fail=lambda a, b: b > 90.0)   # the forward model "fails" in part of the box
    result = fit(predictor, layout(truth), [np.array([1.0, 1.0]), np.array([0.2, 0.3])], max_nfev=100)
    np.testing.assert_allclose(BASE.values(result.u), [0.8, 20.0], rtol=1e-3)
    assert result.start is not None and result.start[1] == 0.3
    with pytest.raises(SpflowError, match="every start"):
        fit(AnalyticPredictor(fail=lambda a, b: True), layout(truth), [np.array([0.5, 0.5])])


def test_multi_start_fit_skips_only_unused_jacobians():
    """The first, budgeted round of a multi-start fit skips the forward runs of its last Jacobians (economy): the
    fit equals the documented procedure run here with plain scipy and a forward-difference Jacobian of the model
    written out in the test (each start 1/3 of the budget, the best one continued with the full budget)."""
    from scipy.optimize import least_squares

    rng = np.random.default_rng(7)
    lay = layout(model(1.2, 80.0, 0.3) + 0.01 * rng.normal(size=PV.size))
    h, max_nfev = 0.01, 12
    starts = [np.array([0.1, 0.9, 0.9]), np.array([0.5, 0.5, 0.5]), np.array([0.9, 0.2, 0.1])]

    def residual(z):
        a, b = BASE.values(z[:2])
        return lay.whiten(model(a, b, EFFECT.value(z[2])) - lay.observed())

    def jacobian(z):
        steps = np.where(z + h <= 1.0, h, -h)
        return np.column_stack([(residual(z + steps[j] * np.eye(3)[j]) - residual(z)) / steps[j] for j in range(3)])

    def solve(z0, budget):
        return least_squares(residual, z0, jac=jacobian, bounds=(0.0, 1.0), method="trf", x_scale=1.0,
                             ftol=1e-4, xtol=1e-4, gtol=1e-6, max_nfev=budget)

    first = [solve(z0, max_nfev // 3) for z0 in starts]
    reference = solve(min(first, key=lambda r: r.cost).x, max_nfev)
    runs = {}
    for economy in (True, False):
        predictor = AnalyticPredictor()
        result = fit(predictor, lay, starts, (EFFECT,), max_nfev=max_nfev, diff_step=h, economy=economy)
        np.testing.assert_allclose(result.z, reference.x, rtol=1e-12, atol=1e-14)
        np.testing.assert_allclose(result.residual, reference.fun, rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(result.jacobian, reference.jac, rtol=1e-9, atol=1e-9)
        runs[economy] = len(predictor.distinct)
    # every start of this noisy problem uses its whole first-round budget: the two starts that are not continued
    # skip one Jacobian each (3 shifted points), the continued one has its Jacobian computed when its full run
    # begins
    assert all(r.nfev == max_nfev // 3 for r in first)
    assert runs[False] - runs[True] == 2 * 3


def test_given_parameter_sets_pick_the_best_member():
    truth = model(1.5, 30.0, 0.0)
    sets = xr.Dataset({"values": (("sample", "param"), [[0.2, 90.0], [1.5, 30.0], [1.0, 50.0]])},
                      coords={"param": ["AD31", "GAMHF"]})
    starts = parameter_set_starts(BASE, sets)
    result = calibrate_base(AnalyticPredictor(), layout(truth), parameter_sets=starts, polish=False)
    np.testing.assert_allclose(BASE.values(result.u), [1.5, 30.0])
    assert result.nfev == 0 and result.chi2 < 1e-20
    with pytest.raises(ParameterError, match="lack parameter 'GAMHF'"):
        parameter_set_starts(BASE, sets.assign_coords(param=["AD31", "X"]))
    # the same members as a design of a log-scale GAMHF column (log10 of the value, as the parameter_space stage
    # writes it): the map the design carries gives the same starting points
    logged = ParameterMap(("AD31", "GAMHF"), (("AD31",), ("GAMHF",)), (False, True)).design(
        [[0.2, np.log10(90.0)], [1.5, np.log10(30.0)], [1.0, np.log10(50.0)]])
    np.testing.assert_allclose(parameter_set_starts(BASE, logged), starts, rtol=1e-12)


LINEAR = BaseModel.from_mapping({"parameters": {"AD31": [0.0, 2.0], "CRK": [0.0, 1.0]}})


class LinearPredictor:
    """y = AD31 + CRK pv: the leave-one-slug-out fits are ordinary least squares with a closed form."""

    base = LINEAR

    def predict(self, points, experiments, variables=None):
        return [{"E": {"y": self.base.values(u)[0] + self.base.values(u)[1] * PV}} for u, _ in points]


def test_leave_one_slug_out_equals_closed_form_least_squares():
    from spflow.plugins.gap.least_squares import Fit
    from spflow.plugins.gap.predictive_scores import leave_one_slug_out

    rng = np.random.default_rng(4)
    sigma = 0.05
    observed = 0.7 + 0.2 * PV + sigma * rng.normal(size=PV.size)
    slugs = np.searchsorted([1.0, 2.5, 99.0], PV - 1e-9)
    lay = Layout((Block("y", "E", np.arange(PV.size), PV, observed, slugs,
                        BlockErrorModel(np.full(PV.size, sigma), 0.0)),))
    full = fit(LinearPredictor(), lay, [np.array([0.5, 0.5])], max_nfev=50, diff_step=1e-7)
    assert isinstance(full, Fit)
    out = leave_one_slug_out(LinearPredictor(), lay, full, max_nfev=50, diff_step=1e-7)
    X = np.column_stack([np.ones(PV.size), PV])
    for s in range(3):
        held = slugs == s
        coef = np.linalg.lstsq(X[~held], observed[~held], rcond=None)[0]
        np.testing.assert_allclose(out.whitened[held], (X[held] @ coef - observed[held]) / sigma, atol=1e-5)
        # the terms of a window: Gaussian with the Laplace parameter covariance of its own fit (prior tau 0.5)
        J = X[~held] / sigma * np.array([2.0, 1.0])              # whitened Jacobian in unit coordinates
        A = X[held] / sigma * np.array([2.0, 1.0])
        S = np.eye(held.sum()) + A @ np.linalg.inv(J.T @ J + 4.0 * np.eye(2)) @ A.T
        w = out.whitened[held]
        expected = -0.5 * w @ np.linalg.solve(S, w) - 0.5 * np.linalg.slogdet(S)[1]
        assert out.lpd[held].sum() == pytest.approx(expected, rel=1e-4)


def test_secant_update_is_the_least_change_satisfying_the_secant_condition():
    """Broyden's update against its definition, solved here as an equality-constrained least-norm problem: the
    matrix J nearest to J0 (Frobenius) with J s = f(z1) - f(z0). The first Jacobian is a forward difference; on an
    affine residual every update keeps the exact matrix."""
    from spflow.plugins.gap.least_squares import SecantJacobian

    rng = np.random.default_rng(3)
    A, c = rng.normal(size=(5, 3)), rng.normal(size=5)

    class Problem:   # residual f(z) = sin(A z) + c, its forward difference with step h (the WhitenedProblem API)
        h, calls = 1e-6, 0

        def fun(self, z):
            return np.sin(A @ z) + c

        def jac(self, z, f0=None):
            self.calls += 1
            return np.column_stack([(self.fun(z + self.h * e) - self.fun(z)) / self.h for e in np.eye(3)])

    problem = Problem()
    secant = SecantJacobian(problem)
    z0, z1, z2 = np.array([0.1, 0.2, 0.3]), np.array([0.15, 0.1, 0.35]), np.array([0.2, 0.12, 0.3])
    J0 = secant(z0)
    np.testing.assert_allclose(J0, np.cos(A @ z0)[:, None] * A, rtol=1e-4, atol=1e-5)   # analytic derivative
    for za, zb in ((z0, z1), (z1, z2)):
        J_prev = J0 if za is z0 else J1
        J1 = secant(zb)
        s, y = zb - za, problem.fun(zb) - problem.fun(za)
        # min ||vec(J) - vec(J_prev)|| s.t. (s^T kron I) vec(J) = y: minimum-norm correction of the constraint
        M = np.stack([np.concatenate([s if k == i else np.zeros(3) for k in range(5)]) for i in range(5)])
        d = np.linalg.lstsq(M, y - J_prev @ s, rcond=None)[0]
        np.testing.assert_allclose(J1, J_prev + d.reshape(5, 3), rtol=1e-10, atol=1e-12)
        np.testing.assert_allclose(J1 @ s, y, rtol=1e-10, atol=1e-12)
    assert problem.calls == 1 and secant.differences == 1
    # affine residual: the forward difference is exact and every update leaves it unchanged
    problem.fun = lambda z: A @ z + c
    affine = SecantJacobian(problem)
    for z in (z0, z1, z2):
        np.testing.assert_allclose(affine(z), A, rtol=1e-6, atol=1e-6)


def test_secant_first_round_follows_the_documented_procedure():
    """first_round="secant": every start runs a third of the budget with one forward-difference Jacobian at the
    start and Broyden updates after it (written out in the test with plain scipy), the best start continues with
    forward differences and the full budget; the first round takes one forward-difference Jacobian per start only."""
    from scipy.optimize import least_squares

    rng = np.random.default_rng(7)
    lay = layout(model(1.2, 80.0, 0.3) + 0.01 * rng.normal(size=PV.size))
    h, max_nfev = 0.01, 15
    starts = [np.array([0.1, 0.9, 0.9]), np.array([0.5, 0.5, 0.5]), np.array([0.9, 0.2, 0.1])]

    seen = set()   # the distinct points the procedure runs

    def residual(z):
        seen.add(tuple(z))
        a, b = BASE.values(z[:2])
        return lay.whiten(model(a, b, EFFECT.value(z[2])) - lay.observed())

    def difference(z):
        steps = np.where(z + h <= 1.0, h, -h)
        return np.column_stack([(residual(z + steps[j] * np.eye(3)[j]) - residual(z)) / steps[j] for j in range(3)])

    def broyden():
        state = {}

        def jac(z):
            if not state:
                state.update(z=z.copy(), J=difference(z))
            else:
                s = z - state["z"]
                y = residual(z) - residual(state["z"])
                if s @ s > 0:
                    state["J"] = state["J"] + np.outer(y - state["J"] @ s, s) / (s @ s)
                state["z"] = z.copy()
            return state["J"]
        return jac

    def solve(z0, budget, jac):
        return least_squares(residual, z0, jac=jac, bounds=(0.0, 1.0), method="trf", x_scale=1.0,
                             ftol=1e-4, xtol=1e-4, gtol=1e-6, max_nfev=budget)

    first = [solve(z0, max_nfev // 3, broyden()) for z0 in starts]
    reference = solve(min(first, key=lambda r: r.cost).x, max_nfev, difference)
    predictor = AnalyticPredictor()
    result = fit(predictor, lay, starts, (EFFECT,), max_nfev=max_nfev, diff_step=h, first_round="secant")
    np.testing.assert_allclose(result.z, reference.x, rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(result.residual, reference.fun, rtol=1e-10, atol=1e-10)
    np.testing.assert_allclose(result.jacobian, reference.jac, rtol=1e-9, atol=1e-9)
    # the forward runs are the points the procedure evaluates, fewer than with forward differences in the first round
    assert len(predictor.distinct) == len(seen)
    every_step = AnalyticPredictor()
    fit(every_step, lay, starts, (EFFECT,), max_nfev=max_nfev, diff_step=h, first_round="difference")
    assert len(predictor.distinct) < len(every_step.distinct)
    with pytest.raises(ParameterError, match="first_round = 'broyden' is not allowed"):
        fit(AnalyticPredictor(), lay, starts, (EFFECT,), first_round="broyden")


def test_first_round_jacobian_option_is_checked_before_any_work():
    from spflow.plugins.gap.diagnosis import Options, diagnose
    from spflow.plugins.gap.stage import Diagnose

    base = BaseModel.from_mapping({"cells": 12, "parameters": {"AP1": [5.0, 40.0]}})
    with pytest.raises(ParameterError, match=r"first_round_jacobian = 'exact' is not allowed; allowed "
                                             r"\['difference', 'secant'\]"):
        diagnose(["no_such_file.nc"], [], base, options=Options(first_round_jacobian="exact"))
    with pytest.raises(ParameterError, match="first_round_jacobian"):
        Diagnose(first_round_jacobian="exact")
    assert Diagnose(first_round_jacobian="difference").options.first_round_jacobian == "difference"
