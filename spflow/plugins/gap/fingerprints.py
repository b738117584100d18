"""Projected fingerprints: what an effect does to the data that re-calibrating the base model cannot absorb.

At the calibrated base point, the fingerprint of candidate ``k`` at a finite test strength ``t`` is the whitened
change of the predictions, ``g = W [y(theta, s_k = t) - y(theta, s_k = b_k)]`` (docs/gap.md, Method: **Which**;
finite strengths rather than derivatives, since a derivative at ``s = 0`` misjudges a finite front shift).
Re-calibration can absorb the part of ``g`` that lies along the
whitened Jacobian ``J`` of the calibrated parameters; what is left is the projected fingerprint ``P g``.

The calibrated parameters can only move inside their ranges, so the nuisance directions are projected out with a
Gaussian prior of scale ``tau`` on the unit-box shift (the marginal, or Bayesian, form of the matched-subspace
detector):

    P = (I + tau^2 J J')^-1 = I - J (J'J + I / tau^2)^-1 J'        (Woodbury)

``tau -> inf`` is the orthogonal projector of the classical score test; with finite ``tau`` a direction the
parameters reach only weakly (a narrow range, e.g. ALPHAL1's +-20 %) is not credited with absorbing a large
effect. With the data residual ``d = W (y_obs - y(theta_hat))`` the screen statistic is the score

    z = <P g, d> / ||P g||_P,    ||x||_P^2 = <x, P x>,

approximately N(0, 1) when the effect is absent; ``z > 0`` means that adding the effect moves the prediction
toward the data. ``||P g||_P`` at the true strength is the fingerprint's signal-to-noise ratio (SNR). The angle
matrix ``cos phi_jk = <P g_j, g_k> / (||P g_j||_P ||P g_k||_P)`` is the a-priori ambiguity of two effects
(|cos| > 0.9: near-collinear, docs/gap.md, Method: **Which**).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

__all__ = ["NuisanceProjector", "ScreenResult", "screen"]


class NuisanceProjector:
    """``P = I - J (J'J + I/tau^2)^-1 J'`` applied without forming the n x n matrix (``tau = inf``: exact)."""

    def __init__(self, jacobian: np.ndarray, tau: float = 0.5):
        self.J = np.asarray(jacobian, dtype=float)
        ridge = 0.0 if not np.isfinite(tau) else 1.0 / tau**2
        gram = self.J.T @ self.J + ridge * np.eye(self.J.shape[1])
        self._solve = np.linalg.pinv(gram, hermitian=True, rcond=1e-10)

    def apply(self, x: np.ndarray) -> np.ndarray:
        return x - self.J @ (self._solve @ (self.J.T @ x))

    def inner(self, x: np.ndarray, y: np.ndarray) -> float:
        """``<x, P y>`` (P is symmetric positive definite for finite tau)."""
        return float(x @ self.apply(y))

    def norm(self, x: np.ndarray) -> float:
        return float(np.sqrt(max(self.inner(x, x), 0.0)))


@dataclass(frozen=True)
class ScreenResult:
    """Per candidate: raw and projected fingerprint norms and the score z at each test strength; angle matrix."""

    names: tuple[str, ...]
    levels: tuple[tuple[float, ...], ...]
    raw_norm: tuple[np.ndarray, ...]
    snr: tuple[np.ndarray, ...]
    z: tuple[np.ndarray, ...]
    cos: np.ndarray
    fingerprints: tuple[np.ndarray, ...]

    def best_z(self) -> np.ndarray:
        return np.array([float(np.max(z)) for z in self.z])

    def absorbed(self, i: int) -> float:
        """Fraction of the reference fingerprint's norm that re-calibration absorbs (1 = indistinguishable)."""
        return float(1.0 - self.snr[i][-1] / self.raw_norm[i][-1]) if self.raw_norm[i][-1] > 0 else 1.0


def screen(names: Sequence[str], levels: Sequence[Sequence[float]], fingerprints: Sequence[np.ndarray],
           data_residual: np.ndarray, projector: NuisanceProjector) -> ScreenResult:
    """Scores and angles of whitened fingerprints ``fingerprints[k]`` (n x n_levels, one column per strength in
    ``levels[k]``) against the whitened data residual ``d = W (y_obs - y_fit)``. The angle matrix uses each
    candidate's last (reference) test strength."""
    raw, snr, z = [], [], []
    for g in fingerprints:
        raw.append(np.linalg.norm(g, axis=0))
        norms = np.array([projector.norm(g[:, j]) for j in range(g.shape[1])])
        snr.append(norms)
        z.append(np.array([projector.inner(g[:, j], data_residual) / n if n > 0 else 0.0
                           for j, n in enumerate(norms)]))
    ref = [g[:, -1] for g in fingerprints]
    k = len(ref)
    cos = np.eye(k)
    for i in range(k):
        for j in range(i + 1, k):
            denom = snr[i][-1] * snr[j][-1]
            cos[i, j] = cos[j, i] = projector.inner(ref[i], ref[j]) / denom if denom > 0 else 0.0
    return ScreenResult(tuple(names), tuple(tuple(map(float, lv)) for lv in levels), tuple(raw), tuple(snr),
                        tuple(z), cos, tuple(fingerprints))
