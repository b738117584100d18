"""Where inside a slug the misfit changes: mean-shift change points in whitened residuals (docs/gap.md,
Method: **Where**).

Change points at slug boundaries are expected and say nothing (the residuals of a gap cell jump where the injected
fluid changes); change points *inside* a slug -- at the polymer breakthrough, when an oil bank or a retention front
reaches the outlet -- localise an unmodelled front. So every (variable, experiment, slug) cell of
:mod:`~spflow.plugins.gap.localisation` is tested on its own.

**Statistic.** For a segment ``x_1..x_n`` of whitened residuals and each split ``k`` (``m <= k <= n - m``, ``m``
the minimum segment length) the two-sample t statistic of a mean shift,

    t_k = (mean(x_{k+1..n}) - mean(x_{1..k})) / (s_k sqrt(1/k + 1/(n-k))),   s_k^2 = max(1, RSS_k / (n - 2)),

with ``RSS_k`` the residual sum of squares of the two-mean fit; ``T = max_k |t_k|`` (the likelihood-ratio CUSUM
test of one mean shift; Worsley 1979, Andrews 1993 sup-F with F = t^2). The whitened residuals have variance 1
under the error model; the scale ``s_k`` is never below it (the test is never more confident than the error model:
stretches of exact zeros, e.g. oil-cut readings clipped at 0 after the oil is gone, do not make change points) and
follows the residual scatter when that is larger (an over-dispersed misfit without a mean shift does not make
change points either). ``T`` does not change under ``x -> x + b``: a constant bias of the cell is the cell's bias
z, not a change point.

**Null.** Under the diagnosis's error model the whitened residuals of a right model are iid N(0, 1)
(:mod:`~spflow.plugins.gap.error_model`: whitening inverts the AR(1) recursion exactly), so the null distribution
of ``T`` depends on ``n`` and ``m`` alone. It is tabulated by Monte Carlo (``draws`` iid normal segments per
``n``) and the p-value is ``(1 + #{T_null >= T}) / (draws + 1)``, an exact test at levels that are multiples of
``1 / (draws + 1)``.

**Binary segmentation.** A cell is split at ``argmax |t_k|`` when ``p < level`` and both halves are tested again
the same way (Vostrikova 1981). Under "no change in the cell" only the first test can reject, so the family-wise
error per cell is ``level``; the diagnosis uses ``level = alpha / #cells`` (Bonferroni, as for the gap cells).

The effect size of a change point is the mean shift of the whitened residuals across it (units of the error
model's sigma) and of the raw residuals (the variable's units), each over the two adjoining segments.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from spflow.core.errors import ParameterError

from .layout import Layout

__all__ = ["ChangePoint", "max_shift_statistic", "null_statistics", "shift_pvalue", "segment", "change_points"]


def _t_profile(x: np.ndarray, m: int) -> np.ndarray:
    """|t_k| for k = m..n-m along the last axis of ``x`` (module docstring)."""
    n = x.shape[-1]
    k = np.arange(m, n - m + 1)
    c1 = np.cumsum(x, axis=-1)
    c2 = np.cumsum(x * x, axis=-1)
    s1, s2 = c1[..., k - 1], c2[..., k - 1]
    t1, t2 = c1[..., -1:], c2[..., -1:]
    mean_l, mean_r = s1 / k, (t1 - s1) / (n - k)
    rss = (s2 - k * mean_l**2) + ((t2 - s2) - (n - k) * mean_r**2)
    s = np.sqrt(np.maximum(rss / (n - 2), 1.0))
    return np.abs(mean_r - mean_l) / (s * np.sqrt(1.0 / k + 1.0 / (n - k)))


def max_shift_statistic(x: np.ndarray, m: int = 3) -> tuple[float, int]:
    """(T, split) of one segment: the largest |t_k| and the number of points before the split."""
    x = np.asarray(x, dtype=float)
    if m < 2 or x.size < 2 * m:
        raise ParameterError(f"a change-point test needs min_segment >= 2 and at least 2 * min_segment points; got "
                             f"min_segment = {m}, {x.size} points")
    t = _t_profile(x, m)
    i = int(np.argmax(t))
    return float(t[i]), m + i


@lru_cache(maxsize=128)
def null_statistics(n: int, m: int, draws: int, seed: int) -> np.ndarray:
    """Sorted Monte Carlo draws of ``T`` for iid normal segments of length ``n`` (cached per process)."""
    rng = np.random.default_rng([seed, n, m])
    out = np.empty(draws)
    chunk = max(1, 2_000_000 // n)
    for a in range(0, draws, chunk):
        out[a: a + chunk] = _t_profile(rng.standard_normal((min(chunk, draws - a), n)), m).max(axis=-1)
    out.sort()
    return out


def shift_pvalue(t: float, n: int, m: int = 3, draws: int = 20000, seed: int = 0) -> float:
    """Monte Carlo p-value ``(1 + #{T_null >= t}) / (draws + 1)`` of ``T = t`` on ``n`` points."""
    null = null_statistics(n, m, draws, seed)
    return float((1 + null.size - np.searchsorted(null, t, side="left")) / (null.size + 1))


def segment(x: np.ndarray, level: float, m: int = 3, draws: int = 20000, seed: int = 0,
            ) -> list[tuple[int, float, float]]:
    """Binary segmentation of ``x`` at test level ``level``: ``(split index, T, p-value)`` of every significant
    change point, ordered by position (the split index is the first point after the change)."""
    if not 0.0 < level < 1.0:
        raise ParameterError(f"change-point test level = {level!r} is out of range; allowed (0, 1)")
    x = np.asarray(x, dtype=float)
    found = []
    stack = [(0, x.size)]
    while stack:
        a, b = stack.pop()
        if b - a < 2 * m:
            continue
        t, k = max_shift_statistic(x[a:b], m)
        p = shift_pvalue(t, b - a, m, draws, seed)
        if p < level:
            found.append((a + k, t, p))
            stack += [(a, a + k), (a + k, b)]
    return sorted(found)


@dataclass(frozen=True)
class ChangePoint:
    """A significant mean shift inside one (variable, experiment, slug) cell."""

    variable: str
    experiment: str
    slug: int
    slug_name: str
    pv: float
    statistic: float
    pvalue: float
    shift_whitened: float
    shift: float


def change_points(layout: Layout, whitened: np.ndarray, residual: np.ndarray, slug_names: dict[str, list[str]],
                  alpha: float, m: int = 3, draws: int = 20000, seed: int = 0) -> list[ChangePoint]:
    """Significant change points inside every cell of ``layout`` (Bonferroni over the cells at ``alpha``), the
    strongest (largest statistic) first. ``pv`` is midway between the last point before and the first after."""
    groups = []
    for block, s in zip(layout.blocks, layout.slices()):
        for slug in np.unique(block.slug):
            groups.append((block, s, int(slug), np.flatnonzero(block.slug == slug)))
    level = alpha / max(len(groups), 1)
    out = []
    for block, s, slug, idx in groups:
        w, e, pv = whitened[s][idx], residual[s][idx], block.pv[idx]
        splits = segment(w, level, m, draws, seed)
        edges = [0] + [k for k, _, _ in splits] + [idx.size]
        for j, (k, t, p) in enumerate(splits, start=1):
            left, right = slice(edges[j - 1], k), slice(k, edges[j + 1])
            out.append(ChangePoint(block.variable, block.experiment, slug, slug_names[block.experiment][slug],
                                   float(0.5 * (pv[k - 1] + pv[k])), t, p,
                                   float(w[right].mean() - w[left].mean()), float(e[right].mean() - e[left].mean())))
    return sorted(out, key=lambda c: -c.statistic)
