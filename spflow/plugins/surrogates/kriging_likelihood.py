"""Maximum-likelihood correlation lengths of universal Kriging (thesis Eq. 3.21), optimised by GPy/paramz.

Eq. 3.21 is the concentrated (profile) likelihood: β̂ and σ̂² are replaced by their GLS closed forms
(:mod:`.kriging`), leaving ½ log|R| + (N/2) log(2πσ̂²) + N/2 to minimise over the correlation lengths θ. For columns
that share θ (one correlation matrix) but keep their own trend and σ̂², the objective is the sum over columns.

GPy has no likelihood for GLS universal Kriging (its ``mean_function`` treats β as free hyperparameters and drops the
trend-uncertainty term; its Bias/Linear-kernel route approximates GLS only as the prior variances grow), so
:class:`ConcentratedLikelihood` is a small ``GPy.core.Model``: it computes Eq. 3.21 and dL/dR with the closed forms and
hands dL/dR to the kernel's ``update_gradients_full``. Everything else is GPy/paramz: the kernels and their gradients,
bounded length scales (logistic transform), L-BFGS-B, and ``optimize_restarts`` for the multi-start.

Multi-start: the first run starts at ℓ = 1 in every direction (the half-width of the [-1, 1] box); every further
run starts at length scales drawn log-uniformly in [0.1, 10] from a seeded generator (paramz's default restart,
N(0, 1) through the logistic transform, would put every start near the middle of the bounds).
"""

from __future__ import annotations

import GPy
import numpy as np

from .kriging import UniversalKriging, check_kernel
from .regression import is_constant

__all__ = ["ConcentratedLikelihood", "fit_lengthscales", "gpy_kernel", "informative_columns", "GPY_KERNELS",
           "LENGTHSCALE_BOUNDS", "START_RANGE"]

#: GPy kernel of each correlation family of :data:`.kriging.KERNELS`.
GPY_KERNELS = {"gaussian": GPy.kern.RBF, "matern52": GPy.kern.Matern52}
#: Allowed correlation lengths ℓ in the [-1, 1] auxiliary space. The upper bound is far beyond the box (an input with
#: ℓ = 10^4 moves the correlation by ~10^-8): an input the response barely depends on (Borehole's r, Tu, Tl) drives
#: its ℓ to the bound, and a bound of 100 kept a spurious dependence that cost 1.1-1.8x in validation error on
#: Borehole at N = 50-400 (issue #24, docs/surrogates.md "Kriging peers"). The restarts still start in START_RANGE.
LENGTHSCALE_BOUNDS = (1e-2, 1e4)
#: Log-uniform range of the random restarts.
START_RANGE = (0.1, 10.0)


def gpy_kernel(name: str, lengthscale: np.ndarray) -> GPy.kern.Kern:
    """The GPy kernel of correlation family ``name`` (variance fixed to 1, ARD ``lengthscale``)."""
    lengthscale = check_kernel(name, lengthscale)
    kern = GPY_KERNELS[name](lengthscale.size, variance=1.0, lengthscale=lengthscale, ARD=True)
    kern.variance.fix()
    return kern


class ConcentratedLikelihood(GPy.core.Model):
    """Eq. 3.21 summed over the columns of ``y`` for correlation family ``kernel`` whose length scales (starting at
    ``start``) are the free parameters; see :class:`~.kriging.UniversalKriging` for ``basis``/``trend``/``nugget``."""

    def __init__(self, z: np.ndarray, y: np.ndarray, basis: np.ndarray, trend: np.ndarray, kernel: str,
                 start: np.ndarray, nugget: float, seed: int):
        super().__init__(name="universal_kriging")
        self.z, self.y, self.basis, self.trend, self.kernel, self.nugget = z, y, basis, trend, kernel, nugget
        self._rng = np.random.default_rng(seed)
        self.kern = gpy_kernel(kernel, start)
        self.kern.lengthscale.constrain_bounded(*LENGTHSCALE_BOUNDS, warning=False)
        self.link_parameter(self.kern)

    def parameters_changed(self) -> None:
        model = UniversalKriging(self.z, self.y, self.basis, self.trend, self.kernel, self.kern.lengthscale.values,
                                 self.nugget)
        self._log_likelihood = model.log_likelihood()
        self.kern.update_gradients_full(model.log_likelihood_gradient_k(), self.z)

    def log_likelihood(self) -> float:
        return self._log_likelihood

    def randomize(self, rand_gen=None, *args, **kwargs) -> None:
        """Restart point for ``optimize_restarts``: log-uniform length scales in :data:`START_RANGE`."""
        lo, hi = np.log(START_RANGE)
        self.kern.lengthscale[:] = np.exp(self._rng.uniform(lo, hi, size=self.kern.lengthscale.size))


def informative_columns(y: np.ndarray, basis: np.ndarray, trend: np.ndarray) -> np.ndarray:
    """Columns that carry information about θ: not constant up to round-off (:func:`.regression.is_constant`) and
    not already reproduced by their trend (least-squares residual above round-off).

    A column fitted exactly by its trend has σ̂² = 0 for every θ, i.e. an infinite likelihood; a column whose spread
    is round-off (recovery before breakthrough) would make θ fit noise. Both are left out of Eq. 3.21.
    """
    keep = ~is_constant(y)
    for j in np.flatnonzero(keep):
        f = basis[:, trend[j]]
        residual = np.linalg.norm(y[:, j] - f @ np.linalg.lstsq(f, y[:, j], rcond=None)[0])
        keep[j] = residual > 1e-10 * np.linalg.norm(y[:, j])
    return np.flatnonzero(keep)


def fit_lengthscales(z: np.ndarray, y: np.ndarray, basis: np.ndarray, trend: np.ndarray, kernel: str,
                     nugget: float, restarts: int, seed: int, start: np.ndarray | None = None) -> np.ndarray:
    """Maximum-likelihood length scales (d,) of the columns of ``y`` sharing one correlation kernel.

    ``restarts`` L-BFGS-B runs (the first from ``start``, default ℓ = 1, moved inside the open bounds); the best
    likelihood wins. Without any informative column (see :func:`informative_columns`) the likelihood is flat in θ and
    the start is returned.
    """
    lo, hi = LENGTHSCALE_BOUNDS
    start = np.ones(z.shape[1]) if start is None else np.clip(start, lo * (1 + 1e-6), hi * (1 - 1e-6))
    columns = informative_columns(y, basis, trend)
    if columns.size == 0:
        return start
    model = ConcentratedLikelihood(z, y[:, columns], basis, trend[columns], kernel, start, nugget, seed)
    model.optimize_restarts(num_restarts=restarts, optimizer="lbfgsb", robust=True, verbose=False)
    return np.array(model.kern.lengthscale.values, dtype=float)
