"""Simulator-based weighted least squares: calibrate the base model (optionally with freed effect strengths).

Minimises ``sum w^2`` of the whitened residuals (:mod:`~spflow.plugins.gap.error_model`) over the calibrated
parameters and the strengths of freed candidate effects, all mapped to the unit box (linear or log scale per
coordinate, :mod:`~spflow.plugins.gap.base_model`), with ``scipy.optimize.least_squares`` (trust-region reflective,
box bounds) from one or several starts. This is the thesis's deterministic calibration (Eqs. 3.16-3.17 weighted
by the measurement error) done on the simulator itself.

The Jacobian is a forward difference of finite size ``diff_step`` in the unit box (1 % of each range by default:
the adaptive time stepping makes the simulator's output jitter at tiny perturbations), its columns evaluated as
one parallel batch by the :class:`~spflow.plugins.gap.prediction.Predictor`; scipy's own finite differences are
serial. The fit keeps the whitened Jacobian at the optimum for the fingerprint projection and for linearised
parameter uncertainty.

A multi-start fit runs every start for a third of the budget and continues the best one with the full budget. The
first round only picks that start, so it may take its Jacobians from Broyden's secant update
(``first_round="secant"``, :class:`SecantJacobian`: one forward-difference Jacobian at the start, then rank-one
updates from the residuals the optimiser evaluates anyway, no forward runs) instead of a forward difference at every
accepted step (``"difference"``). The continued start always uses forward differences, so the reported optimum and
its Jacobian are forward-difference ones either way; the start that wins the first round, and therefore the local
optimum reached, can differ (docs/gap.md, Cost).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy.optimize import least_squares

from spflow.core.errors import ParameterError, SpflowError

from .catalogue import CandidateEffect
from .layout import Layout
from .prediction import Predictor

__all__ = ["FIRST_ROUND_JACOBIANS", "Fit", "fit", "model_point", "SecantJacobian", "WhitenedProblem"]

#: Jacobians of the first, budgeted round of a multi-start fit: a forward difference at every accepted step, or
#: Broyden's secant update from one forward difference at the start (module docstring)
FIRST_ROUND_JACOBIANS = ("difference", "secant")

#: whitened residual assigned to every point when a forward run fails (the optimiser steps back)
_FAILED = 1.0e3


@dataclass
class Fit:
    """A calibrated model: unit-box coordinates ``z`` (calibrated parameters, then freed strengths), the whitened
    residuals and Jacobian there, and the start the optimiser came from."""

    z: np.ndarray
    candidates: tuple[CandidateEffect, ...]
    n_params: int
    residual: np.ndarray
    jacobian: np.ndarray
    nfev: int
    message: str
    start: np.ndarray | None = None

    @property
    def u(self) -> np.ndarray:
        return self.z[: self.n_params]

    @property
    def strengths(self) -> dict[str, float]:
        return {c.name: c.value(v) for c, v in zip(self.candidates, self.z[self.n_params:])}

    @property
    def chi2(self) -> float:
        return float(self.residual @ self.residual)

    @property
    def point(self) -> tuple[np.ndarray, dict[str, float]]:
        return self.u, self.strengths


def model_point(z: np.ndarray, n_params: int, candidates: Sequence[CandidateEffect]):
    """(unit-box parameters, strengths) of a stacked coordinate vector ``z``."""
    return z[:n_params], {c.name: c.value(v) for c, v in zip(candidates, z[n_params:])}


class WhitenedProblem:
    """Whitened residuals ``W (y(z) - y_obs)`` of ``layout`` as a function of stacked unit-box coordinates ``z``,
    and their forward-difference Jacobian (columns as one batch)."""

    def __init__(self, predictor: Predictor, layout: Layout, candidates, n_params: int, diff_step: float):
        self.predictor, self.layout, self.candidates = predictor, layout, tuple(candidates)
        self.n_params, self.h = n_params, diff_step
        self.obs = layout.observed()

    def residuals(self, zs: list[np.ndarray]) -> list[np.ndarray]:
        preds = self.predictor.predict([model_point(z, self.n_params, self.candidates) for z in zs],
                                       self.layout.experiments, self.layout.variables)
        return [np.full(self.layout.size, _FAILED) if p is None
                else self.layout.whiten(self.layout.vector(p) - self.obs) for p in preds]

    def fun(self, z):
        return self.residuals([np.asarray(z, float)])[0]

    def jac(self, z, f0=None):
        z = np.asarray(z, float)
        steps = np.where(z + self.h <= 1.0, self.h, -self.h)
        shifted = [z + steps[j] * np.eye(z.size)[j] for j in range(z.size)]
        f0 = self.fun(z) if f0 is None else f0
        return np.column_stack([(f - f0) / steps[j] for j, f in enumerate(self.residuals(shifted))])


def _without_last_jacobian(problem: WhitenedProblem, budget: int):
    """(residuals, Jacobian) callables for ``least_squares(..., max_nfev=budget)`` that skip the forward runs of
    the Jacobian at the point of the ``budget``-th residual evaluation, returning zeros instead.

    Exact: trust-region reflective counts every residual evaluation (the start's included) and stops as soon as
    the count reaches ``max_nfev``; a Jacobian requested after the ``budget``-th *distinct* evaluated point (at
    most as many as scipy's count) is therefore the last one, used only for the gradient and Jacobian that scipy
    reports with its result -- the iterate ``x`` and the residuals ``fun`` it returns do not depend on it. The
    first, budgeted round of a multi-start fit keeps only those two (the best start's Jacobian is recomputed, from
    memoised runs or new ones, when its full run begins there), so the skipped runs were never used."""
    seen: set[bytes] = set()

    def fun(z):
        z = np.asarray(z, float)
        seen.add(z.tobytes())
        return problem.fun(z)

    def jac(z):
        if len(seen) >= budget:
            return np.zeros((problem.layout.size, np.size(z)))
        return problem.jac(z)

    return fun, jac


class SecantJacobian:
    """Jacobian callable for ``least_squares``: the forward difference of ``problem`` at the first point it is asked
    for, then Broyden's ("good") rank-one update at every later point ``z`` from the last one ``z0``,

        J = J0 + (f(z) - f(z0) - J0 s) s^T / (s^T s),   s = z - z0,

    the least change of ``J0`` (Frobenius norm) that satisfies the secant condition ``J s = f(z) - f(z0)``
    (Broyden 1965; Dennis & Schnabel 1996, Sec. 8.1). scipy's trust-region reflective method asks for the Jacobian
    only at points whose residuals it has just evaluated, which the predictor has memoised: an update costs no
    forward run. ``differences`` counts the forward-difference Jacobians taken."""

    def __init__(self, problem: WhitenedProblem):
        self.problem = problem
        self.z: np.ndarray | None = None
        self.f: np.ndarray | None = None
        self.J: np.ndarray | None = None
        self.differences = 0

    def __call__(self, z) -> np.ndarray:
        z = np.asarray(z, float)
        f = self.problem.fun(z)
        if self.J is None:
            self.J, self.differences = self.problem.jac(z, f), self.differences + 1
        else:
            s = z - self.z
            ss = float(s @ s)
            if ss > 0.0:
                self.J = self.J + np.outer(f - self.f - self.J @ s, s) / ss
        self.z, self.f = z, f
        return self.J.copy()


def fit(predictor: Predictor, layout: Layout, starts: Sequence[np.ndarray], candidates=(), *,
        max_nfev: int = 30, diff_step: float = 0.01, economy: bool = True, first_round: str = "difference") -> Fit:
    """Least-squares fit from the best of ``starts`` (unit-box vectors of length p + len(candidates)).

    With several starts, each first runs a third of the budget; the best one then continues with the full
    ``max_nfev`` (the memoised forward runs make the restart free). ``economy`` skips the forward runs of the
    Jacobians at the end of the first round (:func:`_without_last_jacobian`: same result, fewer runs); ``False``
    computes them (the behaviour before, for benchmarks). ``first_round`` (one of :data:`FIRST_ROUND_JACOBIANS`):
    the Jacobians of that first round, forward differences or Broyden's secant update (:class:`SecantJacobian`; the
    continued start uses forward differences either way)."""
    if first_round not in FIRST_ROUND_JACOBIANS:
        raise ParameterError(f"first_round = {first_round!r} is not allowed; allowed {list(FIRST_ROUND_JACOBIANS)} "
                             "(the Jacobians of a multi-start fit's first round)")
    n_params = len(predictor.base.parameters)
    problem = WhitenedProblem(predictor, layout, candidates, n_params, diff_step)

    def solve(z0, budget, last_jacobian=True, secant=False):
        fun, jac = problem.fun, problem.jac
        if secant:  # (its updates cost no forward run, the last one included)
            jac = SecantJacobian(problem)
        elif not last_jacobian:
            fun, jac = _without_last_jacobian(problem, budget)
        return least_squares(fun, z0, jac=jac, bounds=(0.0, 1.0), method="trf", x_scale=1.0,
                             ftol=1e-4, xtol=1e-4, gtol=1e-6, max_nfev=budget)

    best, best_start = None, None
    for z0 in starts:
        z0 = np.clip(np.asarray(z0, float), 0.0, 1.0)
        if z0.size != n_params + len(problem.candidates):
            raise SpflowError(f"start has {z0.size} coordinates, expected {n_params + len(problem.candidates)}")
        if np.all(problem.fun(z0) == _FAILED):
            continue
        res = (solve(z0, max(2, max_nfev // 3), not economy, first_round == "secant") if len(starts) > 1
               else solve(z0, max_nfev))
        if best is None or res.cost < best.cost:
            best, best_start = res, z0
    if best is None:
        raise SpflowError("every start of the least-squares calibration failed in the forward model")
    if len(starts) > 1:
        best = solve(best.x, max_nfev)
    return Fit(best.x, problem.candidates, n_params, best.fun, best.jac, int(best.nfev), str(best.message),
               best_start)
