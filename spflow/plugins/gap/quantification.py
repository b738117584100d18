"""How far the gap shrinks (docs/gap.md, Method: **How far**): gap closed, RMSE ratios, interval coverage, shifts.

* gap-closed fraction on a data set of ``n`` points fitted with ``p`` parameters:
  ``(chi2_before - chi2_after) / (chi2_before - (n - p))`` — 1 when the model after reaches the noise level,
  NaN when there was no gap (``chi2_before <= n - p``);
* RMSE of the raw residuals per (variable, experiment) block, and the ratio after / before;
* coverage of central ``level`` predictive intervals ``y_fit +- z sqrt(sigma_e^2 + (J_raw C J_raw')_ii)``, where
  ``sigma_e`` is the marginal measurement error (:mod:`~spflow.plugins.gap.error_model`), ``J_raw`` the raw
  Jacobian of the predictions and ``C = (J_w' J_w + I / tau^2)^-1`` the linearised (Laplace) covariance of the
  unit-box coordinates from the whitened calibration Jacobian, with a Gaussian prior of scale ``tau`` standing in
  for the box (no inflation);
* parameter shift in physical units and as a fraction of each parameter's range.
"""

from __future__ import annotations

import numpy as np
from scipy.stats import norm

from .layout import Layout
from .least_squares import Fit, model_point
from .prediction import Predictor

__all__ = ["gap_closed", "raw_jacobian", "parameter_covariance", "predictive_std", "coverage", "block_rmse"]


def gap_closed(chi2_before: float, chi2_after: float, dof: float) -> float:
    """Fraction of the misfit excess over its noise expectation ``dof`` removed by the model after."""
    excess = chi2_before - dof
    return float((chi2_before - chi2_after) / excess) if excess > 0 else float("nan")


def raw_jacobian(predictor: Predictor, layout: Layout, fitted: Fit, h: float = 0.01) -> tuple[np.ndarray, np.ndarray]:
    """(predictions, forward-difference Jacobian w.r.t. the unit-box coordinates) of ``layout`` at ``fitted``
    (NaN predictions if the run there fails; zero columns where a perturbed run fails)."""
    z = fitted.z
    steps = np.where(z + h <= 1.0, h, -h)
    points = [model_point(z, fitted.n_params, fitted.candidates)]
    points += [model_point(z + steps[j] * np.eye(z.size)[j], fitted.n_params, fitted.candidates)
               for j in range(z.size)]
    preds = predictor.predict(points, layout.experiments, layout.variables)
    if preds[0] is None:
        return np.full(layout.size, np.nan), np.zeros((layout.size, z.size))
    y0 = layout.vector(preds[0])
    cols = [np.zeros(layout.size) if p is None else (layout.vector(p) - y0) / steps[j]
            for j, p in enumerate(preds[1:])]
    return y0, np.column_stack(cols)


def parameter_covariance(whitened_jacobian: np.ndarray, tau: float = 0.5) -> np.ndarray:
    """``(J_w' J_w + I / tau^2)^-1``: the linearised posterior covariance of the unit-box coordinates with a
    Gaussian prior of scale ``tau`` (the box bounds the parameters; an inert coordinate gets the prior)."""
    q = whitened_jacobian.shape[1]
    return np.linalg.inv(whitened_jacobian.T @ whitened_jacobian + np.eye(q) / tau**2)


def predictive_std(layout: Layout, jacobian: np.ndarray, covariance: np.ndarray) -> np.ndarray:
    """Marginal predictive standard deviation: measurement error plus linearised parameter uncertainty."""
    param_var = np.einsum("ij,jk,ik->i", jacobian, covariance, jacobian)
    return np.sqrt(layout.marginal_std() ** 2 + np.maximum(param_var, 0.0))


def coverage(residual: np.ndarray, std: np.ndarray, level: float = 0.9) -> float:
    """Fraction of points inside the central ``level`` predictive interval."""
    ok = np.isfinite(residual) & np.isfinite(std)
    return float(np.mean(np.abs(residual[ok]) <= norm.ppf(0.5 + level / 2) * std[ok])) if ok.any() else float("nan")


def block_rmse(layout: Layout, residual: np.ndarray) -> dict[tuple[str, str], float]:
    """RMSE of the raw residuals per (variable, experiment)."""
    return {(b.variable, b.experiment): float(np.sqrt(np.nanmean(residual[s] ** 2)))
            for b, s in zip(layout.blocks, layout.slices())}
