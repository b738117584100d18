"""The per-QoI noise σ_i of thesis Eqs. 4.3-4.4 under Jeffreys' prior, integrated out of the likelihood.

One block i (one QoI of one experiment on the 0.1 PV grid) has n residuals r_k = d_k − f_k(θ) and, from the
surrogate, a known error variance v_k ≥ 0 per point. Its noise model is d_k ~ N(f_k(θ), σ_i² + v_k).

**Prior.** Jeffreys' rule applied to this model: the Fisher information of σ is Σ_k 2σ²/(σ² + v_k)², so

    p(σ) ∝ σ · sqrt( (1/n) Σ_k (σ² + v_k)^-2 ),

normalised so that p(σ) = 1/σ when v ≡ 0 — the thesis's Eq. 4.4 (p(σ²) ∝ 1/σ², i.e. p(σ) ∝ 1/σ). With v > 0 the
plain 1/σ prior would make the marginal diverge (the likelihood tends to a positive constant as σ → 0 and ∫₀ dσ/σ
is infinite); Jeffreys' rule for the model that includes v is finite at σ → 0 and keeps the posterior proper. Its
arbitrary scale is pinned by the σ → ∞ limit, where it equals 1/σ for every θ, so marginals at different θ are
comparable.

**Marginal.** With v ≡ 0 the integral is closed (docs/calibration.md, The posterior):

    p(d | θ) = ∫₀^∞ N(d | f, σ² I) σ^-1 dσ = ½ Γ(n/2) π^(-n/2) S^(-n/2),   S = Σ_k r_k².

With v > 0 there is no closed form; the 1-D integral is taken in u = log σ² by the trapezoidal rule on a sinh map
u = c + s·sinh(t) centred on the integrand's mode c (safeguarded Newton on its derivative, bracketed) with the
Laplace width s; the rule converges exponentially for this smooth, exponentially decaying integrand (absolute error
of log p below 1e-5 over residual and variance scales spanning ten decades; see the tests against
``scipy.integrate.quad``). The same nodes give draws of σ from its conditional posterior p(σ | θ, d), used for
posterior-predictive noise; with v ≡ 0 that conditional is exactly σ² ~ Inv-Gamma(n/2, S/2).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit
from scipy.special import gammaln

__all__ = ["log_marginal_closed_form", "log_marginal", "log_marginal_checked", "log_sigma_prior", "sample_sigma"]

#: Trapezoid step in t of the sinh map (absolute accuracy of log p about 1e-6; halving it costs twice as much).
STEP = 0.2
#: How far (in units of u = log σ²) the nodes reach on either side of the mode before the tails are negligible.
REACH = 40.0
#: ``uniforms`` argument of :func:`_quadrature` when no σ is to be drawn.
_NO_DRAWS = np.empty(0)


def log_marginal_closed_form(sum_sq: np.ndarray, n: int) -> np.ndarray:
    """log ∫ N(d | f, σ²I) σ⁻¹ dσ = log(½ Γ(n/2)) − (n/2) log(π S) for residual sums of squares ``sum_sq``."""
    return gammaln(n / 2.0) - math.log(2.0) - 0.5 * n * np.log(math.pi * np.asarray(sum_sq, dtype=float))


def log_sigma_prior(sigma: np.ndarray, v: np.ndarray) -> np.ndarray:
    """log p(log σ) = log(σ² sqrt(mean_k (σ² + v_k)^-2)) for σ (W,) and v (W, n): Jeffreys' rule in log σ
    (0 if v ≡ 0)."""
    s2 = np.asarray(sigma, dtype=float)[:, None] ** 2
    return np.log(s2[:, 0]) + 0.5 * np.log(np.mean((s2 + v) ** -2.0, axis=1))


@njit(cache=True)
def _log_integrand(u, r2, v):  # pragma: no cover - compiled
    """log of N(r | 0, e^u + v) · p(σ) dσ/du at u = log σ² (the integrand of the marginal in u)."""
    w = math.exp(u)
    n = r2.size
    ll = 0.0
    q = 0.0
    for k in range(n):
        a = w + v[k]
        ll -= math.log(2.0 * math.pi * a) + r2[k] / a
        q += 1.0 / (a * a)
    return 0.5 * ll + math.log(0.5) + u + 0.5 * math.log(q / n)


@njit(cache=True)
def _derivatives(u, r2, v):  # pragma: no cover - compiled
    """First and second derivative of :func:`_log_integrand` in u."""
    w = math.exp(u)
    s1 = s2 = sv = s3 = q2 = q3 = q4 = 0.0
    for k in range(r2.size):
        ia = 1.0 / (w + v[k])
        ia2 = ia * ia
        ia3 = ia2 * ia
        s1 += ia
        s2 += r2[k] * ia2
        sv += v[k] * ia2
        s3 += r2[k] * (v[k] - w) * ia3
        q2 += ia2
        q3 += ia3
        q4 += ia2 * ia2
    d1 = -0.5 * w * s1 + 0.5 * w * s2 + 1.0 - w * q3 / q2
    d2 = -0.5 * w * sv + 0.5 * w * s3 - w * q3 / q2 + 3.0 * w * w * q4 / q2 - 2.0 * w * w * q3 * q3 / (q2 * q2)
    return d1, d2


@njit(cache=True)
def _mode(r2, v):  # pragma: no cover - compiled
    """Mode c of the integrand in u and its Laplace width s (safeguarded Newton inside a sign-change bracket)."""
    n = r2.size
    total = 0.0
    for k in range(n):
        total += r2[k] + v[k]
    top = math.log(max(total / n, 1e-300))
    lo, hi = top - 10.0, top + 3.0
    while _derivatives(lo, r2, v)[0] <= 0.0:  # the derivative tends to +1 as u -> -inf
        lo -= 10.0
    while _derivatives(hi, r2, v)[0] >= 0.0:  # and to -n/2 as u -> +inf
        hi += 3.0
    c = 0.5 * (lo + hi)
    for _ in range(100):
        d1, d2 = _derivatives(c, r2, v)
        if d1 > 0.0:
            lo = c
        else:
            hi = c
        nxt = c - d1 / d2 if d2 < 0.0 else 0.5 * (lo + hi)
        if not lo < nxt < hi:
            nxt = 0.5 * (lo + hi)
        done = abs(nxt - c) < 1e-12 * max(1.0, abs(c)) or hi - lo < 1e-12
        c = nxt
        if done:
            break
    d2 = _derivatives(c, r2, v)[1]
    s = 1.0 / math.sqrt(-d2) if d2 < 0.0 else 1.0
    return c, s


@njit(cache=True)
def _quadrature(r2, v, uniforms, step, reach):  # pragma: no cover - compiled
    """Per row: log marginal and, if ``uniforms`` has one number per row, a draw of log σ from p(σ | θ, d)."""
    rows, n = r2.shape
    logz = np.empty(rows)
    log_sigma = np.full(rows, np.nan)
    for i in range(rows):
        c, s = _mode(r2[i], v[i])
        half = int(math.ceil(math.asinh(reach / s) / step))
        vals = np.empty(2 * half + 1)
        peak = -np.inf
        for j in range(-half, half + 1):
            t = j * step
            val = _log_integrand(c + s * math.sinh(t), r2[i], v[i]) + math.log(step * s * math.cosh(t))
            vals[j + half] = val
            peak = max(peak, val)
        acc = 0.0
        for j in range(vals.size):
            vals[j] = math.exp(vals[j] - peak)
            acc += vals[j]
        logz[i] = peak + math.log(acc)
        if uniforms.size == rows:  # node by its mass, then uniformly within its cell of width `step` in t
            target = uniforms[i] * acc
            cum = 0.0
            j = 0
            while j < vals.size - 1 and cum + vals[j] < target:
                cum += vals[j]
                j += 1
            t = (j - half) * step + step * ((target - cum) / vals[j] - 0.5)
            log_sigma[i] = 0.5 * (c + s * math.sinh(t))
    return logz, log_sigma


def _check(residuals: np.ndarray, variance: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    r = np.atleast_2d(np.asarray(residuals, dtype=float))
    v = np.ascontiguousarray(np.broadcast_to(np.asarray(variance, dtype=float), r.shape))
    if (v < 0).any():
        raise ValueError("surrogate error variances must be >= 0")
    return r, v


def log_marginal(residuals: np.ndarray, variance: np.ndarray | float = 0.0) -> np.ndarray:
    """log p(d | θ) of one block with σ integrated out under the Jeffreys prior above.

    ``residuals`` (W, n) are d − f(θ) for W parameter vectors, ``variance`` (W, n) (or broadcastable) the surrogate's
    error variance at the same points. Rows whose variance is all zero use the closed form (exact); the others the
    quadrature.
    """
    return log_marginal_checked(*_check(residuals, variance))


def log_marginal_checked(r: np.ndarray, v: np.ndarray | None) -> np.ndarray:
    """:func:`log_marginal` without input validation, for a caller that guarantees float arrays ``r`` (W, n) and
    ``v`` (W, n) C-contiguous with ``v >= 0`` — or ``v = None`` for v ≡ 0 (closed form, no test of v). The MCMC hot
    path (:class:`~.likelihood.PosteriorModel`) validates its shapes once and clips the surrogate's variance."""
    r2 = r * r
    if v is None:
        return log_marginal_closed_form(np.sum(r2, axis=1), r.shape[1])
    mixed = v.any(axis=1)
    if mixed.all():  # the usual case with a surrogate error: no closed form to compute and overwrite
        return _quadrature(r2, v, _NO_DRAWS, STEP, _reach(r.shape[1]))[0]
    out = log_marginal_closed_form(np.sum(r2, axis=1), r.shape[1])
    if mixed.any():
        rows = np.flatnonzero(mixed)
        out[rows] = _quadrature(r2[rows], v[rows], _NO_DRAWS, STEP, _reach(r.shape[1]))[0]
    return out


def sample_sigma(residuals: np.ndarray, variance: np.ndarray | float, rng: np.random.Generator) -> np.ndarray:
    """Draws of σ (W,) from p(σ | θ, d) for each row: exact Inv-Gamma(n/2, S/2) for σ² where v ≡ 0, else from the
    quadrature nodes (the mass of each node, spread uniformly over its cell)."""
    r, v = _check(residuals, variance)
    n = r.shape[1]
    sigma = np.sqrt(0.5 * np.sum(r * r, axis=1) / rng.gamma(0.5 * n, 1.0, size=r.shape[0]))
    mixed = np.flatnonzero(v.any(axis=1))
    if mixed.size:
        uniforms = rng.random(mixed.size)
        sigma[mixed] = np.exp(_quadrature(r[mixed] ** 2, v[mixed], uniforms, STEP, _reach(n))[1])
    return sigma


def _reach(n: int) -> float:
    """Reach in u: the right tail decays like exp(−(n/2)u), the left one at least like exp(u)."""
    return REACH / min(1.0, n / 2.0)
