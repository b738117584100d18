"""Pareto fronts of minimised objectives: non-dominated filtering, hypervolume (moocore) and the reference point.

Thesis §4.7: a design dominates another when it is no worse in both objectives and better in one; the Pareto front
is the set of non-dominated designs and its quality is the hypervolume it dominates up to a reference point r.
"""

from __future__ import annotations

import moocore
import numpy as np

from spflow.core.errors import ParameterError

__all__ = ["nondominated", "hypervolume", "reference_point"]


def _points(values: np.ndarray, what: str) -> np.ndarray:
    values = np.asarray(values, dtype=float)
    if values.ndim != 2 or values.shape[1] != 2 or not np.isfinite(values).all():
        raise ParameterError(f"{what} must be a finite (n, 2) array of objective values, got shape {values.shape}")
    return values


def nondominated(values: np.ndarray) -> np.ndarray:
    """Indices (ascending in the first objective) of the non-dominated rows of ``values`` (n, 2); duplicates once."""
    values = _points(values, "objective values")
    index = np.flatnonzero(moocore.is_nondominated(values, maximise=False, keep_weakly=False))
    return index[np.argsort(values[index, 0], kind="stable")]


def hypervolume(values: np.ndarray, reference: np.ndarray) -> float:
    """Hypervolume dominated by the rows of ``values`` (n, 2) and bounded by ``reference`` (moocore, exact)."""
    values = _points(values, "objective values")
    reference = np.asarray(reference, dtype=float)
    if reference.shape != (2,) or not np.isfinite(reference).all():
        raise ParameterError(f"hypervolume reference must be 2 finite numbers, got {reference}")
    inside = values[(values < reference).all(axis=1)]
    return float(moocore.hypervolume(inside, ref=reference)) if inside.size else 0.0


def reference_point(values: np.ndarray, margin: float = 0.1, previous: np.ndarray | None = None) -> np.ndarray:
    """Reference point r = max + margin·(max − min) of ``values`` (n, 2) per objective, never below ``previous``.

    The rule of pydes (Pandita et al. 2018; docs/eeihv.md §3) mirrored for minimisation: r lies beyond the worst
    projected value so that
    every projected design, including the extremes of the front, adds hypervolume; it only ever moves outwards so
    that hypervolumes of later iterations stay comparable. A zero range falls back to a unit margin.
    """
    values = _points(values, "objective values")
    low, high = values.min(axis=0), values.max(axis=0)
    span = np.where(high > low, high - low, 1.0)
    r = high + margin * span
    return r if previous is None else np.maximum(r, previous)
