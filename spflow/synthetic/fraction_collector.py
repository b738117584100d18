"""Effluent fraction collector: fixed-volume tubes, oil read on a graduated scale, amounts per tube.

The collector cuts the effluent into tubes of ``tube_pv`` pore volumes. What a tube holds is the integral of an
interval signal (see :mod:`spflow.synthetic.dead_volume` for the convention) between the tube's edges; for a
piecewise-constant signal the running integral is piecewise linear, so it is evaluated exactly by linear
interpolation of its values at the grid points.

The lab reads each tube's oil column on a scale graduated every ``resolution`` ml: the reading is the true volume
plus an error uniform on [-resolution/2, +resolution/2], independent between tubes (each tube is read once, by
eye), kept inside the physical range [0, tube volume]; a tube without oil (true volume below 1e-9 ml) reads 0
(there is no oil column to misread). The clipping at 0 biases tubes holding less than resolution/2 of oil upward
by at most resolution/8 on average; the error of any reading never exceeds resolution/2. Oil cut per tube and
cumulative recovery follow from the readings exactly as a lab computes them (``docs/data.md``).
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["tube_edges", "running_integral", "tube_amounts", "read_oil_volumes"]

#: a tube with less oil than this (ml) holds none: it reads 0
_NO_OIL_ML = 1.0e-9


def tube_edges(total_pv: float, tube_pv: float) -> np.ndarray:
    """Edges ``0, tube_pv, 2 tube_pv, ...`` of the full tubes collected up to ``total_pv`` (PV)."""
    n = int(math.floor(total_pv / tube_pv + 1.0e-9))
    if n < 1:
        raise ValueError(f"tube_pv = {tube_pv!r} PV exceeds the injected volume {total_pv!r} PV; allowed (0, "
                         f"{total_pv:g}] PV")
    return np.minimum(np.arange(n + 1, dtype=np.float64) * tube_pv, total_pv)  # no round-off past the end


def running_integral(pv: np.ndarray, values: np.ndarray, points: np.ndarray) -> np.ndarray:
    """``integral_0^t values d(pv)`` at each ``t`` in ``points`` (inside ``[0, pv[-1]]``) for an interval signal."""
    cumulative = np.concatenate(([0.0], np.cumsum(values[1:] * np.diff(pv))))
    if np.any(points < pv[0]) or np.any(points > pv[-1] * (1.0 + 1.0e-12)):
        raise ValueError(f"integration points must lie in [{pv[0]:g}, {pv[-1]:g}] PV")
    return np.interp(points, pv, cumulative)


def tube_amounts(pv: np.ndarray, values: np.ndarray, edges: np.ndarray) -> np.ndarray:
    """Per-tube integral of the interval signal (``values`` x PV) between consecutive ``edges``."""
    return np.diff(running_integral(pv, values, edges))


def read_oil_volumes(true_ml: np.ndarray, tube_ml: float, resolution_ml: float,
                     rng: np.random.Generator) -> np.ndarray:
    """Readings (ml) of the tubes' oil volumes: true + U(-resolution/2, resolution/2), clipped to [0, tube_ml];
    exactly 0 for a tube without oil.

    Always draws ``len(true_ml)`` uniforms from ``rng`` (so streams stay aligned whatever the resolution).
    """
    error = (rng.random(len(true_ml)) - 0.5) * resolution_ml
    return np.where(true_ml > _NO_OIL_ML, np.clip(true_ml + error, 0.0, tube_ml), 0.0)
