"""Ordinary least squares for many outputs at once, with the PCE error estimates of thesis §3.5.2.

Solves Eq. 3.6, ``y_α = (ΨᵀΨ)⁻¹ Ψᵀ Y``, for every column of ``Y`` through one SVD of Ψ (the hat matrix, its diagonal
``h`` and ``tr((ΨᵀΨ)⁻¹)`` depend only on Ψ, so the errors of all outputs cost one factorisation). Conventions follow
UQLab (Blatman & Sudret 2011; docs/surrogates.md, Coefficients):

* ``Var̂(y)`` is the population variance (divided by N); a constant output has all errors 0. "Constant" means a
  spread at round-off level, std(y) <= 1e-8 max|y| (:func:`is_constant`): the simulator's recovery before breakthrough
  is exactly 0.125 k at 0.1k PV up to accumulated round-off of ~1e-10, and scoring such a column as an unpredictable
  output (ε_LOO ≈ 1) would swamp ε^mean (Eq. 3.9);
* normalised empirical error (Eq. 3.7): ε_emp = (1/N) Σ e_i² / Var̂(y);
* leave-one-out error (Eq. 3.8) from the hat matrix: ε_LOO = (1/N) Σ (e_i / (1 − h_i))² / Var̂(y);
* modified LOO (Chapelle et al. 2002; Blatman 2009 eq. 5.13): ε*_LOO = T(P, N) ε_LOO with
  T = N / (N − P) · (1 + tr((ΨᵀΨ)⁻¹)), and T = ∞ when N ≤ P.

Condition check: when σ_min/σ_max < 1e-12 the fit falls back to the pseudo-inverse (singular values below that ratio
are dropped, as ``numpy.linalg.pinv`` does); ``OLSFit.rank`` records the rank used.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from spflow.core.errors import ParameterError

__all__ = ["OLSFit", "ols", "relative_errors", "loo_correction", "is_constant"]

#: Smallest accepted σ_min/σ_max of Ψ before falling back to the pseudo-inverse (UQLab's rcond limit).
RCOND = 1e-12
#: Relative spread below which an output counts as constant (round-off of the simulator).
ROUNDOFF = 1e-8


@dataclass(frozen=True)
class OLSFit:
    """Least-squares coefficients and error estimates; per-output arrays have length ``m`` (one per column of Y).

    ``coefficients`` is (P, m); ``leverage`` is the hat-matrix diagonal h (N,); ``correction`` is T(P, N).
    """

    coefficients: np.ndarray
    empirical: np.ndarray
    loo: np.ndarray
    modified_loo: np.ndarray
    leverage: np.ndarray
    correction: float
    rank: int


def loo_correction(n: int, p: int, trace_inverse: float) -> float:
    """T(P, N) = N / (N − P) · (1 + tr((ΨᵀΨ)⁻¹)) of the modified LOO; ∞ when N ≤ P."""
    return n / (n - p) * (1.0 + trace_inverse) if n > p else np.inf


def is_constant(y: np.ndarray) -> np.ndarray:
    """Per column of ``y`` (N, m): True where std(y) <= ROUNDOFF · max|y| (round-off-level spread)."""
    return y.std(axis=0) <= ROUNDOFF * np.abs(y).max(axis=0, initial=0.0)


def relative_errors(y: np.ndarray, residuals: np.ndarray, leverage: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(ε_emp, ε_LOO) of Eqs. 3.7-3.8 per column, from residuals ``y − Ψc`` (N, m) and the hat diagonal (N, ...).

    ``leverage`` broadcasts against ``residuals`` (one h per point for a common Ψ, or one column per active set).
    Constant outputs get 0; a leverage of 1 (a point the fit interpolates exactly) gives ε_LOO = ∞.
    """
    var = y.var(axis=0)
    with np.errstate(divide="ignore", invalid="ignore"):
        emp = np.mean(residuals**2, axis=0) / var
        loo = np.mean((residuals / (1.0 - leverage)) ** 2, axis=0) / var
    zero = is_constant(y)
    emp, loo = np.where(zero, 0.0, emp), np.where(zero, 0.0, loo)
    return emp, np.where(np.isnan(loo), np.inf, loo)


def ols(psi: np.ndarray, y: np.ndarray) -> OLSFit:
    """OLS fit of every column of ``y`` (N,) or (N, m) on the regressors ``psi`` (N, P), with its error estimates."""
    psi = np.asarray(psi, dtype=float)
    y = np.asarray(y, dtype=float)
    if psi.ndim != 2 or y.ndim not in (1, 2) or y.shape[0] != psi.shape[0]:
        raise ParameterError(f"ols: need psi (N, P) and y (N,) or (N, m) with the same N; got psi {psi.shape}, "
                             f"y {y.shape}")
    if not (np.isfinite(psi).all() and np.isfinite(y).all()):
        raise ParameterError("ols: psi and y must be finite")
    y2 = y.reshape(y.shape[0], -1)
    n, p = psi.shape
    u, s, vt = np.linalg.svd(psi, full_matrices=False)
    keep = s > RCOND * s[0] if s.size and s[0] > 0 else np.zeros(s.size, bool)
    u, s, vt = u[:, keep], s[keep], vt[keep]
    coef = vt.T @ ((u.T @ y2) / s[:, None])
    h = np.sum(u**2, axis=1)
    emp, loo = relative_errors(y2, y2 - psi @ coef, h[:, None])
    t = loo_correction(n, p, float(np.sum(1.0 / s**2)))
    with np.errstate(invalid="ignore"):
        modified = np.where(loo == 0.0, 0.0, t * loo)
    squeeze = (lambda a: a[..., 0]) if y.ndim == 1 else (lambda a: a)
    return OLSFit(squeeze(coef), squeeze(emp), squeeze(loo), squeeze(modified), h, t, int(keep.sum()))
