"""Closed-form two-objective extended expected improvement over the dominated hypervolume (EEIHV, thesis §4.7).

Both objectives are **minimised**. With the current (projected, noise-free) Pareto front 𝒫̃ = {p⁽¹⁾…p⁽ᵏ⁾} sorted by
p₁ ascending (so p₂ descending), a reference point r that every front point strictly dominates, and a candidate
whose latent objectives are independent F_j ~ N(μ_j, s_j²) (one GP per objective, Pandita et al. 2018, the thesis's
ref. [214]),

    EEIHV = E[HV(𝒫̃ ∪ {F}; r) − HV(𝒫̃; r)] = ∫∫_A P(F₁ ≤ z₁) P(F₂ ≤ z₂) dz,

with A the part of the box below r that 𝒫̃ does not dominate. A splits into k+1 vertical strips: strip i covers
z₁ ∈ [b_{i−1}, b_i) and z₂ < c_i with breakpoints b = (p₁⁽¹⁾, …, p₁⁽ᵏ⁾, r₁), b₋₁ = −∞, and ceilings
c = (r₂, p₂⁽¹⁾, …, p₂⁽ᵏ⁾). Because ∫_{−∞}^t P(F ≤ z) dz = E[(t − F)⁺] =: EI(t; μ, s),

    EEIHV = Σ_i [EI(b_i; μ₁, s₁) − EI(b_{i−1}; μ₁, s₁)] · EI(c_i; μ₂, s₂),   EI(−∞) = 0,
    EI(t; μ, s) = (t − μ) Φ(u) + s φ(u),   u = (t − μ)/s,

and the exact derivatives ∂EI/∂μ = −Φ(u), ∂EI/∂s = φ(u) give the gradient in O(k) (docs/eeihv.md §2; Pandita et al. 2018
write it for maximisation, this is its mirror image). The formula is vectorised over candidates.
"""

from __future__ import annotations

import numpy as np
from scipy.special import ndtr

from spflow.core.errors import ParameterError

__all__ = ["expected_shortfall", "eeihv", "eeihv_and_gradient"]

_INV_SQRT_2PI = 1.0 / np.sqrt(2.0 * np.pi)
_TINY = 1e-300  # s is floored here so that s = 0 gives the deterministic limit (t − μ)⁺ without 0/0


def expected_shortfall(t: np.ndarray, mu: np.ndarray, s: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """EI(t; μ, s) = E[(t − F)⁺] for F ~ N(μ, s²), with ∂EI/∂μ = −Φ(u) and ∂EI/∂s = φ(u) (broadcast arrays)."""
    s = np.maximum(s, _TINY)
    u = (t - mu) / s
    cdf = ndtr(u)
    with np.errstate(over="ignore"):  # |u| → ∞ as s → 0: φ(u) → 0
        pdf = _INV_SQRT_2PI * np.exp(-0.5 * u**2)
    return (t - mu) * cdf + s * pdf, -cdf, pdf


def _strips(front: np.ndarray, reference: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Strip breakpoints b (k+1,) and ceilings c (k+1,) of the region not dominated by ``front`` below ``reference``.

    Points not strictly dominating the reference add no hypervolume and are dropped; ``front`` must otherwise be
    mutually non-dominated (see :func:`spflow.plugins.slug_design.pareto_front.nondominated`).
    """
    front = np.asarray(front, dtype=float).reshape(-1, 2)
    reference = np.asarray(reference, dtype=float)
    if reference.shape != (2,) or not np.isfinite(reference).all():
        raise ParameterError(f"EEIHV reference must be 2 finite numbers, got {reference}")
    if not np.isfinite(front).all():
        raise ParameterError("EEIHV front must be finite")
    front = front[(front < reference).all(axis=1)]
    front = front[np.argsort(front[:, 0], kind="stable")]
    if front.shape[0] > 1 and (np.diff(front[:, 1]) >= 0).any():
        raise ParameterError("EEIHV front must be non-dominated (p₂ strictly decreasing when sorted by p₁)")
    return np.append(front[:, 0], reference[0]), np.insert(front[:, 1], 0, reference[1])


def _check(mu: np.ndarray, s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    mu = np.atleast_2d(np.asarray(mu, dtype=float))
    s = np.atleast_2d(np.asarray(s, dtype=float))
    if mu.ndim != 2 or mu.shape[1] != 2 or s.shape != mu.shape:
        raise ParameterError(f"EEIHV mu and s must both have shape (m, 2), got {mu.shape} and {s.shape}")
    if (s < 0).any() or not (np.isfinite(mu).all() and np.isfinite(s).all()):
        raise ParameterError("EEIHV mu must be finite and s finite and >= 0")
    return mu, s


def eeihv(mu: np.ndarray, s: np.ndarray, front: np.ndarray, reference: np.ndarray) -> np.ndarray:
    """EEIHV (m,) of m candidates with predictive means ``mu`` (m, 2) and latent standard deviations ``s`` (m, 2)."""
    return eeihv_and_gradient(mu, s, front, reference)[0]


def eeihv_and_gradient(mu: np.ndarray, s: np.ndarray, front: np.ndarray,
                       reference: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """EEIHV (m,) and its exact derivatives with respect to ``mu`` (m, 2) and ``s`` (m, 2)."""
    mu, s = _check(mu, s)
    b, c = _strips(front, reference)
    e1, dmu1, ds1 = expected_shortfall(b[None, :], mu[:, :1], s[:, :1])  # (m, k+1) at the breakpoints
    e2, dmu2, ds2 = expected_shortfall(c[None, :], mu[:, 1:], s[:, 1:])  # (m, k+1) at the ceilings

    def strip_width(a: np.ndarray) -> np.ndarray:  # a(b_i) − a(b_{i−1}), with a(−∞) = 0 for EI, Φ and φ alike
        return np.diff(a, axis=1, prepend=0.0)

    width = strip_width(e1)
    value = np.sum(width * e2, axis=1)
    grad_mu = np.column_stack([np.sum(strip_width(dmu1) * e2, axis=1), np.sum(width * dmu2, axis=1)])
    grad_s = np.column_stack([np.sum(strip_width(ds1) * e2, axis=1), np.sum(width * ds2, axis=1)])
    return value, grad_mu, grad_s
