"""PSIS-LOO of calibrated models on their calibration data (Vehtari, Gelman &
Gabry 2017; docs/gap.md, Method: **Scores** — the secondary score).

A fitted model's posterior is the linearised (Laplace) one of :mod:`~spflow.plugins.gap.quantification`:
unit-box coordinates ``z ~ N(z_hat, C)``, ``C = (J_w' J_w + I / tau^2)^-1``. Along it the whitened calibration
residuals are linear, ``w(z) = r + J_w (z - z_hat)`` (``r``, ``J_w`` from the fit: no forward runs), and the
pointwise log-likelihood of point ``i`` under the shared AR(1) error model is the sequential term

    log p(y_i | y_<i, z) = -w_i(z)^2 / 2 - log a_i - log(2 pi) / 2

(:mod:`~spflow.plugins.gap.error_model`; the ``log a_i`` term is the same for every model and is dropped). From
``draws`` posterior draws, Pareto-smoothed importance sampling (Vehtari, Gelman & Gabry 2017; ``arviz.loo``) gives
the leave-one-out ELPD per point and the Pareto ``k`` diagnostic (``k > 0.7``: that point's estimate is unreliable).
A point the parameters do not move (a zero Jacobian row, e.g. the oil cut before breakthrough) has the same
log-likelihood at every draw: leaving it out does not change the posterior, its LOO term is that value and its
``k`` is undefined (NaN; importance sampling would report ``inf`` for the degenerate constant weights).
Two models fitted to the same data are compared by ``dELPD_loo = sum_i (loo_k,i - loo_ref,i)`` with the pointwise
SE ``sqrt(n var_i)`` of ``arviz.compare``.

Unlike the held-out score of :mod:`~spflow.plugins.gap.predictive_scores`, LOO re-uses the calibration data: for a
one-parameter extension it is close to half the calibration chi^2 drop minus the extra effective parameter, so it
inherits the calibration fit's confounding (a wrong effect that bends the fit scores as well as a right one). It is
reported next to the primary score, not used by the decision rule.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np

from spflow.core.errors import ParameterError
from spflow.plugins.calibration.diagnostics import arviz

from .least_squares import Fit
from .quantification import parameter_covariance

__all__ = ["Loo", "pointwise_log_likelihood", "psis_loo", "compare_loo"]


@dataclass(frozen=True)
class Loo:
    """PSIS-LOO of one model: total ELPD, its SE, effective parameters, pointwise ELPD and Pareto k."""

    elpd: float
    se: float
    p_loo: float
    pointwise: np.ndarray
    pareto_k: np.ndarray


def pointwise_log_likelihood(residual: np.ndarray, jacobian: np.ndarray, covariance: np.ndarray, draws: int,
                             rng: np.random.Generator) -> np.ndarray:
    """(draws, n) log-likelihood terms ``-w_i(z)^2 / 2 - log(2 pi) / 2`` at posterior draws of the coordinates."""
    dz = rng.multivariate_normal(np.zeros(covariance.shape[0]), covariance, size=draws, method="eigh")
    w = residual[None, :] + dz @ jacobian.T
    return -0.5 * w**2 - 0.5 * np.log(2.0 * np.pi)


def psis_loo(fitted: Fit, tau: float = 0.5, draws: int = 2000, seed: int = 0) -> Loo:
    """PSIS-LOO of ``fitted`` on its calibration data (module docstring)."""
    if draws < 100:
        raise ParameterError(f"PSIS-LOO needs draws >= 100 for the Pareto tail fit; got draws = {draws}")
    ok = np.isfinite(fitted.residual)
    cov = parameter_covariance(fitted.jacobian[ok], tau)
    ll = pointwise_log_likelihood(fitted.residual[ok], fitted.jacobian[ok], cov, draws, np.random.default_rng(seed))
    moved = np.ptp(ll, axis=0) > 1e-12 * np.maximum(1.0, np.abs(ll[0]))
    pointwise = np.full(fitted.residual.size, np.nan)
    pareto_k = np.full(fitted.residual.size, np.nan)
    terms, ks = ll[0].copy(), np.full(ll.shape[1], np.nan)
    if moved.any():
        az = arviz()
        data = az.from_dict(posterior={"z": np.zeros((1, draws))}, log_likelihood={"y": ll[None, :, moved]})
        with warnings.catch_warnings():  # k > 0.7 is reported per point (``pareto_k``), not warned about
            warnings.filterwarnings("ignore", message="Estimated shape parameter of Pareto", category=UserWarning)
            result = az.loo(data, pointwise=True)
        terms[moved], ks[moved] = np.asarray(result.loo_i), np.asarray(result.pareto_k)
    pointwise[ok], pareto_k[ok] = terms, ks
    # effective parameters: the log pointwise predictive density minus the LOO ELPD (as arviz.loo)
    lppd = np.log(np.mean(np.exp(ll - ll.max(axis=0)), axis=0)) + ll.max(axis=0)
    return Loo(float(terms.sum()), float(np.sqrt(terms.size * terms.var())), float(lppd.sum() - terms.sum()),
               pointwise, pareto_k)


def compare_loo(model: Loo, reference: Loo) -> tuple[float, float]:
    """(dELPD_loo, pointwise SE) of ``model`` over ``reference`` (same data)."""
    d = model.pointwise - reference.pointwise
    d = d[np.isfinite(d)]
    if d.size < 2:
        return float("nan"), float("nan")
    return float(d.sum()), float(np.sqrt(d.size * d.var(ddof=1)))
