"""Where the calibrated model misses: normalised chi^2 per QoI x slug, residual whiteness, ranked gap cells.

A *cell* is one (variable, experiment, slug) window: the points of a block (:mod:`~spflow.plugins.gap.layout`)
measured while that slug was being injected (windows from the schedule's cumulative slug volumes, Table 2.5;
effluent responses lag their slug by about one PV, so an effluent gap often shows in the *next* slug's window).
Per cell, from the whitened residuals ``w`` (iid N(0, 1) when the model is right):

* normalised chi^2 = mean(w^2) (expected 1) and its p-value ``P(chi^2_n >= sum w^2)``;
* bias z = sum(w) / sqrt(n) (a systematic offset, N(0, 1) under the model);
* RMS of the unwhitened residual in the variable's units (the gap's size in lab terms).

Gap cells are the cells whose p-value passes a Bonferroni test at level ``alpha`` over all cells, ranked by their
excess ``sum w^2 - n``. Whiteness per block: the Ljung-Box statistic (Ljung & Box 1978)

    Q = n (n + 2) sum_{k=1..h} rho_k^2 / (n - k),   p = P(chi^2_h >= Q),   h = min(10, n // 5),

with ``rho_k`` the lag-k autocorrelation of ``w`` about zero (the whitened residuals have mean 0 under the model).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.stats import chi2

from .layout import Layout

__all__ = ["Cell", "cells", "gap_cells", "ljung_box"]


@dataclass(frozen=True)
class Cell:
    """One (variable, experiment, slug) window of whitened residuals."""

    variable: str
    experiment: str
    slug: int
    slug_name: str
    pv_start: float
    pv_end: float
    n: int
    chi2: float
    bias_z: float
    rms: float

    @property
    def normalised_chi2(self) -> float:
        return self.chi2 / self.n

    @property
    def pvalue(self) -> float:
        return float(chi2.sf(self.chi2, self.n))

    @property
    def excess(self) -> float:
        return self.chi2 - self.n


def cells(layout: Layout, whitened: np.ndarray, residual: np.ndarray, slug_names: dict[str, list[str]]) -> list[Cell]:
    """Cells of every block of ``layout`` for whitened residuals ``whitened`` and raw residuals ``residual``."""
    out = []
    for block, s in zip(layout.blocks, layout.slices()):
        w, e = whitened[s], residual[s]
        for slug in np.unique(block.slug):
            m = block.slug == slug
            out.append(Cell(block.variable, block.experiment, int(slug), slug_names[block.experiment][int(slug)],
                            float(block.pv[m].min()), float(block.pv[m].max()), int(m.sum()),
                            float(np.sum(w[m] ** 2)), float(np.sum(w[m]) / np.sqrt(m.sum())),
                            float(np.sqrt(np.mean(e[m] ** 2)))))
    return out


def gap_cells(all_cells: list[Cell], alpha: float) -> list[Cell]:
    """Cells significant at Bonferroni level ``alpha`` (over all cells), largest chi^2 excess first."""
    level = alpha / max(len(all_cells), 1)
    return sorted((c for c in all_cells if c.pvalue < level), key=lambda c: -c.excess)


def ljung_box(w: np.ndarray, lags: int | None = None) -> tuple[float, float, int]:
    """(Q, p-value, lags) of the Ljung-Box test of whiteness of ``w`` (module docstring)."""
    w = np.asarray(w, dtype=float)
    n = w.size
    h = lags if lags is not None else min(10, n // 5)
    if h < 1:
        return float("nan"), float("nan"), 0
    denom = float(w @ w)
    rho = np.array([float(w[k:] @ w[:-k]) / denom for k in range(1, h + 1)])
    q = n * (n + 2) * float(np.sum(rho**2 / (n - np.arange(1, h + 1))))
    return q, float(chi2.sf(q, h)), h
