"""The two misfit measures of the NSGA-II history match, on predictions aligned with observations by label.

* :func:`half_squared_misfit` — the loss of Eq. 3.16, ℓ(P(ξ), y) = ½‖P(ξ) − y‖²₂ = ½ Σ_j (P_j(ξ) − y_j)², one value
  per (variable, experiment) pair; with the pairs (recovery, BCF1) and (dp, BCF1) these are the objectives q_1, q_2
  of Eq. 3.17.
* :func:`relative_l2_misfit` — ‖P(ξ) − y‖₂ / ‖y‖₂ per pair, the relative L2 misfit whose mean over the held-out
  corefloods and the Pareto set is σ_loss (§3.7, Algorithm 3 line 15).

Both take a prediction matrix (n_points, n_output) whose columns are labelled by the
:class:`~spflow.plugins.surrogates.outputs.OutputIndex` that ``aligned`` was built from, and return (n_points,
n_pairs). Only PV points with a finite observation enter (:func:`~spflow.plugins.calibration.aligned_data.align`).
"""

from __future__ import annotations

import numpy as np

from spflow.core.errors import ParameterError
from spflow.plugins.calibration.aligned_data import AlignedData

__all__ = ["half_squared_misfit", "relative_l2_misfit", "residuals"]


def residuals(prediction: np.ndarray, aligned: AlignedData, pairs: list[tuple[str, str]]):
    """For each pair in order: the residuals P − y (n_points, n_block) and the observations y (n_block,)."""
    prediction = np.atleast_2d(prediction)
    for variable, experiment in pairs:
        observed = aligned.observed(variable, experiment)
        yield aligned.predicted(prediction, variable, experiment) - observed, observed


def half_squared_misfit(prediction: np.ndarray, aligned: AlignedData, pairs: list[tuple[str, str]]) -> np.ndarray:
    """Eq. 3.16 for each pair: ½ Σ_j (P_j − y_j)², shape (n_points, n_pairs), in the variable's unit squared."""
    return np.stack([0.5 * np.sum(r**2, axis=-1) for r, _ in residuals(prediction, aligned, pairs)], axis=-1)


def relative_l2_misfit(prediction: np.ndarray, aligned: AlignedData, pairs: list[tuple[str, str]]) -> np.ndarray:
    """‖P − y‖₂ / ‖y‖₂ for each pair, shape (n_points, n_pairs), dimensionless; an all-zero observation raises."""
    out = []
    for (variable, experiment), (r, y) in zip(pairs, residuals(prediction, aligned, pairs)):
        scale = np.linalg.norm(y)
        if scale == 0.0:
            raise ParameterError(f"relative misfit of {variable!r} in {experiment!r}: the observations are all zero")
        out.append(np.linalg.norm(r, axis=-1) / scale)
    return np.stack(out, axis=-1)
