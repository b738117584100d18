"""Out-of-sample scores of calibrated models: held-out experiments, or leave-one-slug-out (docs/gap.md,
Method: **Scores**).

A calibrated model predicts held-out data ``y`` with the Gaussian predictive distribution of its linearised
(Laplace) posterior: mean ``y_fit`` and, in the whitened space of the shared error model,

    S = I + A C A',     A = W J_raw,   C = (J_w' J_w + I / tau^2)^-1

(``J_raw`` the Jacobian of the held-out predictions, ``J_w`` the whitened Jacobian of the calibration fit; see
:mod:`~spflow.plugins.gap.quantification`). The parameter term matters: a model calibrated on one coreflood
mispredicts another partly because its parameters are uncertain, and a candidate must not be credited for that.
With ``S = L L'`` and ``u = L^-1 w`` (``w`` the whitened residuals) the log predictive density splits into
sequential pointwise terms (``p(y_1) p(y_2 | y_1) ...``)

    lpd_i = -u_i^2 / 2 - log L_ii      (constants shared by all models dropped),

and the expected log predictive density (ELPD) difference of model ``k`` over a reference is
``dELPD = sum_i (lpd_k,i - lpd_ref,i)``. Held-out points are experiments not used in the calibration or, without
those, each slug window of the calibration experiments predicted by the model re-fitted without that window
(leave-one-slug-out, the time-series-safe cross-validation; Bürkner, Gabry & Vehtari 2020 on plain LOO
being optimistic for time series).

Two standard errors are reported. The decision uses the **measurement SE**, the delta-method spread of
``dELPD`` over the held-out measurement errors: ``||S_k^-1 w_k - S_ref^-1 w_ref||`` (for ``C = 0`` exactly
``||w_k - w_ref||``). The **pointwise SE** ``sqrt(n var_i(lpd_k,i - lpd_ref,i))`` of ``loo_compare`` treats the
points as exchangeable draws; for a localised gap the gain sits in the few points where the gap is, so this SE is
of the order of the gain itself however large the gain (it is reported, not used).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.linalg import cho_solve, cholesky, solve_triangular

from .layout import Layout
from .least_squares import Fit, fit
from .prediction import Predictor
from .quantification import parameter_covariance, raw_jacobian

__all__ = ["Predictive", "predictive", "leave_one_slug_out", "compare"]


@dataclass(frozen=True)
class Predictive:
    """Pointwise log predictive densities of held-out points, ``S^-1 w`` and the plain whitened residuals; for a
    sampled predictive (:mod:`~spflow.plugins.gap.sampled_predictive`) also the draws' effective sample size and
    the Pareto k of their importance weights and the Monte Carlo standard error of the total (NaN for the
    linearised one)."""

    lpd: np.ndarray
    gradient: np.ndarray
    whitened: np.ndarray
    ess: float = float("nan")
    pareto_k: float = float("nan")
    mcse: float = float("nan")

    @property
    def total(self) -> float:
        return float(np.sum(self.lpd))


def _terms(w: np.ndarray, a: np.ndarray, cov: np.ndarray) -> Predictive:
    factor = cholesky(np.eye(w.size) + a @ cov @ a.T, lower=True)
    u = solve_triangular(factor, w, lower=True)
    return Predictive(-0.5 * u**2 - np.log(np.diag(factor)), cho_solve((factor, True), w), w)


def predictive(predictor: Predictor, layout: Layout, fitted: Fit, tau: float = 0.5, h: float = 0.01,
               rows: np.ndarray | None = None, shift: np.ndarray | None = None) -> Predictive:
    """Predictive terms of the points of ``layout`` (or of its ``rows``) under ``fitted`` (module docstring), its
    mean moved by ``shift`` (raw units; a transferred discrepancy) when given."""
    y, jac = raw_jacobian(predictor, layout, fitted, h)
    if shift is not None:
        y = y + shift
    w = layout.whiten(y - layout.observed())
    a = layout.whiten(jac)
    keep = np.ones(layout.size, bool) if rows is None else rows
    return _terms(w[keep], a[keep], parameter_covariance(fitted.jacobian, tau))


def leave_one_slug_out(predictor: Predictor, layout: Layout, fitted: Fit, *, tau: float = 0.5, max_nfev: int = 10,
                       diff_step: float = 0.01) -> Predictive:
    """Predictive terms of every point of ``layout`` under the model re-fitted (warm start at ``fitted``) without
    the point's (experiment, slug) window; the terms of each window are decorrelated within the window."""
    labels = np.concatenate([[f"{b.experiment}:{s}" for s in b.slug] for b in layout.blocks])
    lpd, grad, white = (np.full(layout.size, np.nan) for _ in range(3))
    for fold in np.unique(labels):
        held = labels == fold
        if held.all():
            continue
        refit = fit(predictor, layout.subset(~held), [fitted.z], fitted.candidates, max_nfev=max_nfev,
                    diff_step=diff_step)
        part = predictive(predictor, layout, refit, tau, diff_step, rows=held)
        lpd[held], grad[held], white[held] = part.lpd, part.gradient, part.whitened
    return Predictive(lpd, grad, white)


def compare(model: Predictive, reference: Predictive) -> tuple[float, float, float]:
    """(dELPD, measurement SE, pointwise SE) of ``model`` over ``reference`` (module docstring)."""
    ok = np.isfinite(model.lpd) & np.isfinite(reference.lpd)
    if not ok.any():
        return float("nan"), float("nan"), float("nan")
    d = model.lpd[ok] - reference.lpd[ok]
    pointwise = float(np.sqrt(d.size * d.var(ddof=1))) if d.size > 1 else float("nan")
    return float(d.sum()), float(np.linalg.norm(model.gradient[ok] - reference.gradient[ok])), pointwise
