"""Measuring sampled numerical results against the analytic references (numpy only, no simulator import).

Cell averages of an exact profile (the fair comparison for a finite-volume solution across a shock), L1 errors,
level-crossing times of effluent histories and the observed order of convergence of a refinement study.
"""

import numpy as np


def cell_average(exact, n_cells: int, samples_per_cell: int = 32):
    """Average of ``exact(x_D)`` over each of ``n_cells`` equal cells of ``[0, 1]`` (midpoint sub-sampling)."""
    if n_cells < 1 or samples_per_cell < 1:
        raise ValueError(f"n_cells and samples_per_cell must be >= 1, got {n_cells}, {samples_per_cell}")
    offsets = (np.arange(samples_per_cell) + 0.5) / samples_per_cell
    x = (np.arange(n_cells)[:, None] + offsets[None, :]) / n_cells
    return np.asarray(exact(x.ravel()), dtype=float).reshape(n_cells, samples_per_cell).mean(axis=1)


def l1_error(numerical, reference_cell_averages) -> float:
    """``int_0^1 |u_num - u_exact| dx_D`` on a uniform grid, given the exact profile's cell averages."""
    numerical = np.asarray(numerical, dtype=float)
    reference = np.asarray(reference_cell_averages, dtype=float)
    if numerical.shape != reference.shape or numerical.ndim != 1:
        raise ValueError(f"profiles must be 1-D of equal shape, got {numerical.shape} and {reference.shape}")
    return float(np.mean(np.abs(numerical - reference)))


def crossing_time(t, y, level: float) -> float:
    """First ``t`` at which ``y`` reaches ``level`` (rising or falling), linearly interpolated between samples."""
    t = np.asarray(t, dtype=float)
    y = np.asarray(y, dtype=float) - level
    if y[0] == 0.0:
        return float(t[0])
    hits = np.nonzero(np.sign(y[1:]) != np.sign(y[0]))[0]
    if hits.size == 0:
        raise ValueError(f"the series never reaches level {level} (range [{y.min() + level}, {y.max() + level}])")
    k = int(hits[0])
    return float(t[k] - y[k] * (t[k + 1] - t[k]) / (y[k + 1] - y[k]))


def interval_midpoints(pv):
    """Times to attach to samples averaged over ``(previous grid point, pv]`` (the first sample stays at ``pv[0]``)."""
    pv = np.asarray(pv, dtype=float)
    return pv - 0.5 * np.diff(pv, prepend=pv[0])


def observed_order(n_cells, errors) -> float:
    """Least-squares slope ``p`` of ``log(error) = c - p log(N)`` over a refinement study."""
    n_cells, errors = np.asarray(n_cells, dtype=float), np.asarray(errors, dtype=float)
    if n_cells.size < 2 or np.any(errors <= 0.0):
        raise ValueError("need at least two positive errors")
    return float(-np.polyfit(np.log(n_cells), np.log(errors), 1)[0])
