"""The ``gp`` surrogate kind: a plain Gaussian process, i.e. ordinary Kriging (constant trend; thesis Eq. 3.18 with
P(ξ) = 1), with the same kernels, maximum-likelihood length scales, storage and output sharing as PC-Kriging
(:mod:`.kriging_surrogate`). The baseline PC-Kriging is compared with.
"""

from __future__ import annotations

import numpy as np

from .kriging_surrogate import NUGGET, RESTARTS, KrigingSurrogate
from .outputs import OutputIndex

__all__ = ["GP"]


class GP(KrigingSurrogate):
    """Ordinary-Kriging Gaussian process; build with :meth:`fit` (or the ``gp`` stage)."""

    kind = "gp"
    label = "GP"

    @classmethod
    def fit(cls, names: list[str], lower: np.ndarray, upper: np.ndarray, outputs: OutputIndex, x: np.ndarray,
            y: np.ndarray, *, kernel: str = "gaussian", share: str = "output", nugget: float = NUGGET,
            restarts: int = RESTARTS, seed: int = 0, parallel=None, progress=None, inputs=None) -> GP:
        """Fit on points ``x`` (N, d) in physical units and outputs ``y`` (N, m); the inputs are uniform on the box
        unless ``inputs`` gives their marginals (:mod:`.input_marginals`): the kernel then acts on their reference
        variables (:meth:`to_unit`), e.g. (x − mean)/std for a normal input."""
        constant = np.zeros((1, len(names)), dtype=np.int64)
        orders = [np.zeros(1, dtype=np.int64)] * len(outputs)
        return cls.fit_trends(names, lower, upper, outputs, x, y, constant, orders, mode="sequential",
                              kernel=kernel, share=share, nugget=nugget, restarts=restarts, seed=seed,
                              parallel=parallel, progress=progress, inputs=inputs)
