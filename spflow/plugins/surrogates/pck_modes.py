"""PC-Kriging calibration modes (Schöbi, Sudret & Wiart 2015; UQLab ``Mode``), thesis §3.8 / Eq. 3.19.

Each output column comes with its trend candidates *ranked* by hybrid LARS (constant first, :mod:`.lars`). For a
group of columns that share one correlation kernel:

* ``sequential`` (UQLab's default, the thesis's choice): every column's trend is its whole LARS-selected set; the
  correlation lengths are fitted once by maximum likelihood (:func:`.kriging_likelihood.fit_lengthscales`).
* ``optimal``: for k = 1, 2, ..., the trend of each column is its first k ranked polynomials (all of them if it has
  fewer); the lengths are re-fitted by maximum likelihood for each k, and the k with the smallest Kriging LOO error
  (Dubrule, ε_LOO of Eq. 3.8 averaged over the group's columns, Eq. 3.9) is kept. UQLab pays one full calibration per
  k; here k = 1 gets the multi-start and every later k one L-BFGS-B run warm-started at the previous optimum, which
  moves little from one k to the next.

With one rank-1 candidate (the constant) per column, ``sequential`` is ordinary Kriging: the plain GP surrogate.
"""

from __future__ import annotations

import numpy as np

from spflow.core.errors import ParameterError

from .blas import single_threaded_blas
from .kriging import UniversalKriging

__all__ = ["MODES", "trend_mask", "fit_group"]

MODES = ("sequential", "optimal")


def trend_mask(orders: list[np.ndarray], n_basis: int, k: int | None = None) -> np.ndarray:
    """(m, n_basis) mask of the first ``k`` ranked terms of each column (all of them for ``k=None``)."""
    mask = np.zeros((len(orders), n_basis), dtype=bool)
    for j, order in enumerate(orders):
        mask[j, np.asarray(order[:k], dtype=np.int64)] = True
    return mask


def fit_group(z: np.ndarray, y: np.ndarray, basis: np.ndarray, orders: list[np.ndarray], mode: str, kernel: str,
              nugget: float, restarts: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """Trend mask (m, P) and length scales (d,) of one group of columns ``y`` (n, m) at points ``z`` (n, d).

    ``basis`` (n, P) holds the trend candidates at ``z``; ``orders[j]`` lists column j's candidates in LARS order.
    """
    from .kriging_likelihood import fit_lengthscales  # GPy/SciPy's optimisers load when lengths are fitted

    if mode not in MODES:
        raise ParameterError(f"PC-Kriging mode {mode!r} is not known; allowed: {list(MODES)}")
    with single_threaded_blas():  # small factorisations (GPy's kernels too); parallelism is over groups
        if mode == "sequential":
            mask = trend_mask(orders, basis.shape[1])
            return mask, fit_lengthscales(z, y, basis, mask, kernel, nugget, restarts, seed)
        best = (np.inf, None, None)
        lengths = None
        for k in range(1, max(len(o) for o in orders) + 1):
            mask = trend_mask(orders, basis.shape[1], k)
            lengths = fit_lengthscales(z, y, basis, mask, kernel, nugget, restarts if k == 1 else 1, seed, lengths)
            model = UniversalKriging(z, y, basis, mask, kernel, lengths, nugget)
            score = float(np.mean(model.relative_loo()))
            if best[1] is None or score < best[0]:
                best = (score, mask, lengths)
        return best[1], best[2]
