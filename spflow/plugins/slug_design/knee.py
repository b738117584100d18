"""Knee point of a two-objective Pareto front by the minimum-distance selection method (TMDSM; thesis §4.7, refs.
[237, 238], Figs. 4.9-4.10).

Each (minimised) objective is normalised to [0, 1] over the front, (f − min)/(max − min), so that the utopia point
(the best value of each objective) is the origin; the knee design is the front point nearest to it in Euclidean
distance. The normalisation makes the choice independent of the objectives' units.
"""

from __future__ import annotations

import numpy as np

from spflow.core.errors import ParameterError

__all__ = ["knee_point"]


def knee_point(front: np.ndarray) -> int:
    """Row index of the TMDSM knee of ``front`` (k, 2), both objectives minimised (k >= 1)."""
    front = np.asarray(front, dtype=float)
    if front.ndim != 2 or front.shape[1] != 2 or front.shape[0] < 1 or not np.isfinite(front).all():
        raise ParameterError(f"knee_point: front must be a finite (k >= 1, 2) array, got shape {front.shape}")
    low, span = front.min(axis=0), np.ptp(front, axis=0)
    normalised = (front - low) / np.where(span > 0, span, 1.0)
    return int(np.argmin(np.hypot(normalised[:, 0], normalised[:, 1])))
