"""The generic-discrepancy competitor: a smooth, mechanism-free correction every physical candidate must beat.

In the spirit of Kennedy & O'Hagan (2001) and Brynjarsdóttir & O'Hagan (2014) -- reality = simulator + delta +
noise -- the calibrated base model is given a flexible discrepancy ``delta`` fitted on the calibration data:
per block (observed variable x experiment) and per slug window inside it (coreflood responses jump at slug
changes, so one smooth function across a slug boundary would be wrong: docs/gap.md, Method: **Competitor**), a
Legendre polynomial in
PV of degree ``degree`` (fewer terms in a window with few points), fitted by generalised least squares in the
block's own AR(1) error metric:

    c = argmin || W (r + B c) ||^2,     r = y_base - y_obs,     delta = B c

(``W`` the whitening of :mod:`~spflow.plugins.gap.error_model`). In sample such a delta closes almost any gap; a
discrepancy, however, carries no mechanism and does not transfer to another schedule. Its **held-out prediction**
is its best transferable guess: per (variable, slug name), the mean fitted delta over the calibration points
injected under a slug of that name (e.g. the mean chase-water Δp bias), zero for slug names the calibration
corefloods lack. A physical effect earns its name only when it predicts the held-out coreflood better than the
base model *and* better than this competitor, by the decision rule's margins (:mod:`~spflow.plugins.gap.verdict`):
a mechanism transfers, a bias pattern does not (docs/gap.md, Method: **Competitor**;
Brynjarsdóttir & O'Hagan 2014 on why a flexible discrepancy alone does not identify the physics).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.polynomial import legendre

from .layout import Layout

__all__ = ["Discrepancy", "legendre_basis", "fit_discrepancy"]


def legendre_basis(pv: np.ndarray, degree: int) -> np.ndarray:
    """Legendre polynomials P_0..P_degree of ``pv`` mapped onto [-1, 1] over its range, shape (n, degree + 1);
    the degree is cut to ``n - 1`` for ``n`` points (a constant for a single point)."""
    pv = np.asarray(pv, float)
    degree = max(0, min(degree, pv.size - 1))
    span = pv.max() - pv.min()
    x = np.zeros_like(pv) if span == 0.0 else 2.0 * (pv - pv.min()) / span - 1.0
    return legendre.legvander(x, degree)


@dataclass(frozen=True)
class Discrepancy:
    """A fitted discrepancy: ``delta`` on the calibration layout's points (model + delta ~ data), the whitened
    chi^2 left after it, its number of coefficients, and the per (variable, slug name) means it transfers."""

    delta: np.ndarray
    chi2: float
    n_terms: int
    transfer: dict[tuple[str, str], float]

    def shift(self, layout: Layout, slug_names: Mapping[str, Sequence[str]]) -> np.ndarray:
        """The transferred discrepancy on the points of ``layout`` (raw units; 0 for unseen slug names)."""
        parts = []
        for b in layout.blocks:
            names = slug_names[b.experiment]
            parts.append(np.array([self.transfer.get((b.variable, names[k]), 0.0) for k in b.slug]))
        return np.concatenate(parts) if parts else np.zeros(0)


def fit_discrepancy(layout: Layout, residual: np.ndarray, slug_names: Mapping[str, Sequence[str]],
                    degree: int = 2) -> Discrepancy:
    """The discrepancy of a model with residuals ``residual = y_model - y_obs`` on ``layout`` (module docstring);
    ``slug_names`` maps each experiment to the names of its slugs."""
    delta = np.zeros(layout.size)
    whitened = np.zeros(layout.size)
    n_terms = 0
    for b, s in zip(layout.blocks, layout.slices()):
        basis = np.zeros((b.index.size, 0))
        for k in np.unique(b.slug):
            rows = b.slug == k
            local = legendre_basis(b.pv[rows], degree)
            part = np.zeros((b.index.size, local.shape[1]))
            part[rows] = local
            basis = np.hstack((basis, part))
        r = residual[s]
        coef, *_ = np.linalg.lstsq(b.noise.whiten(basis), -b.noise.whiten(r), rcond=None)
        delta[s] = basis @ coef
        whitened[s] = b.noise.whiten(r + delta[s])
        n_terms += basis.shape[1]
    sums: dict[tuple[str, str], list[float]] = {}
    for b, s in zip(layout.blocks, layout.slices()):
        names = slug_names[b.experiment]
        for k, d in zip(b.slug, delta[s]):
            sums.setdefault((b.variable, names[k]), []).append(float(d))
    transfer = {key: float(np.mean(v)) for key, v in sums.items()}
    return Discrepancy(delta, float(whitened @ whitened), n_terms, transfer)
