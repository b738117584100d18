"""The assignment of training points to the K folds of a cross-validation (shared by the cross-validation of the
whole PCE fit, :mod:`.pce_cross_validation`, and the one that chooses the LARS ranking, :mod:`.lars`).

Folds: the permutation ``numpy.random.default_rng(FOLD_SEED).permutation(N)`` split by ``numpy.array_split`` into K
consecutive parts (sizes differ by at most one).
"""

from __future__ import annotations

import numpy as np

__all__ = ["FOLD_SEED", "fold_indices"]

#: Seed of the permutation that assigns the training points to folds.
FOLD_SEED = 0


def fold_indices(n: int, folds: int) -> list[np.ndarray]:
    """The held-out indices of each of ``folds`` folds of ``n`` points (rule above)."""
    return np.array_split(np.random.default_rng(FOLD_SEED).permutation(n), folds)
