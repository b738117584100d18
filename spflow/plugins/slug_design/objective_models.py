"""One Gaussian-process surrogate per objective for EEIHV (thesis §4.7; Pandita et al. 2018, ref. [214]).

Each objective k gets a GPy ``GPRegression`` with an ARD Matérn kernel and a *learned* homoscedastic Gaussian noise
variance σ_n,k²: the noise stands for the parametric uncertainty (posterior parameter draws, oil-price paths) that each
objective call samples once, so the GP mean filters it out without modelling the random parameters. Inputs are scaled
to the unit cube by the design bounds and outputs standardised by the data mean and standard deviation; the
hyperparameters are fitted by maximum likelihood (GPy ``optimize``) from a default, a warm and seeded random starts.

All public methods work in physical units. The predictive distribution used by EEIHV is the *latent* (noise-free)
one, f(x) ~ N(m(x), s²(x)) (``predict_noiseless``), and its gradients come from GPy's ``predictive_gradients``:
∂s/∂x = (∂s²/∂x)/(2s), with s² floored at a tiny positive value (pydes' √(v − σ_n²) could go negative).
"""

from __future__ import annotations

from contextlib import AbstractContextManager, contextmanager
from dataclasses import dataclass
from functools import cache

import GPy
import numpy as np
from threadpoolctl import ThreadpoolController

from spflow.core.errors import ParameterError

__all__ = ["GP_KERNELS", "ObjectiveGP"]

#: Kernel families (GPy classes, ARD).
GP_KERNELS = {"matern32": GPy.kern.Matern32, "matern52": GPy.kern.Matern52, "rbf": GPy.kern.RBF}

_VARIANCE_FLOOR = 1e-12  # latent variance floor, relative to the output variance
# Bounds of the standardised hyperparameters: the noise floor keeps the kernel matrix well conditioned; length
# scales (unit-cube inputs) beyond 100 mean "irrelevant input" (unbounded ones overflowed GPy's gradients), and
# below 0.05 the GP turns into spikes between a few dozen designs.
_NOISE_BOUNDS = (1e-6, 10.0)
_LENGTHSCALE_BOUNDS = (5e-2, 1e2)
_SIGNAL_BOUNDS = (1e-3, 1e2)
_FANTASY_NOISE = 1e-8  # standardised noise variance of a fantasised (latent) observation: jitter only


@cache
def _controller() -> ThreadpoolController:
    return ThreadpoolController()


def _single_threaded() -> AbstractContextManager:
    """One BLAS *and* one OpenMP thread: GPy's Cython kernel gradients use OpenMP, and on a busy machine its thread
    team made a one-point ``predictive_gradients`` 50x slower (27 ms instead of 0.5 ms, measured)."""
    return _controller().limit(limits=1)


@contextmanager
def _seeded_global_rng(seed: int):
    """GPy's ``randomize`` draws from numpy's global generator: seed it, then restore the caller's state."""
    state = np.random.get_state()
    np.random.seed(seed)
    try:
        yield
    finally:
        np.random.set_state(state)


@dataclass
class ObjectiveGP:
    """A fitted GP of one objective; build it with :meth:`fit`.

    ``model`` works on unit-cube inputs z = (x − lower)/(upper − lower) and standardised outputs (y − shift)/scale.
    """

    model: GPy.core.GP
    lower: np.ndarray
    upper: np.ndarray
    shift: float
    scale: float

    @classmethod
    def fit(cls, x: np.ndarray, y: np.ndarray, bounds: np.ndarray, *, kernel: str = "matern52",
            restarts: int = 3, seed: int = 0, start: "ObjectiveGP | None" = None) -> "ObjectiveGP":
        """Maximum-likelihood GP of observations ``y`` (n,) at designs ``x`` (n, d) inside ``bounds`` (d, 2).

        The likelihood is maximised from the default start (length scales 0.3 of the box, unit signal variance,
        noise 0.1 of the output variance), from ``start``'s hyperparameters when given (the previous BGO
        iteration's fit), and from ``restarts`` − 1 random points; the best optimum is kept. Both fixed starts
        matter: a warm start alone can keep a run in a degenerate optimum (seen on noisy ZDT1: a length scale
        pinned at its lower bound).
        """
        if kernel not in GP_KERNELS:
            raise ParameterError(f"GP kernel {kernel!r} is not known; allowed: {sorted(GP_KERNELS)}")
        if restarts < 1:
            raise ParameterError(f"GP restarts must be >= 1, got {restarts}")
        x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float).ravel()
        lower, upper = np.asarray(bounds, dtype=float).T
        scale = float(np.std(y))
        scale = scale if scale > 0 else 1.0
        shift = float(np.mean(y))
        z = (x - lower) / (upper - lower)
        kern = GP_KERNELS[kernel](z.shape[1], ARD=True, lengthscale=0.3)
        model = GPy.models.GPRegression(z, ((y - shift) / scale)[:, None], kernel=kern, noise_var=0.1)
        model.Gaussian_noise.variance.constrain_bounded(*_NOISE_BOUNDS, warning=False)
        kern.lengthscale.constrain_bounded(*_LENGTHSCALE_BOUNDS, warning=False)
        kern.variance.constrain_bounded(*_SIGNAL_BOUNDS, warning=False)
        starts = [model.param_array.copy()] + ([start.model.param_array.copy()] if start is not None else [])
        optima = []
        with _single_threaded(), _seeded_global_rng(seed):
            for i in range(len(starts) + restarts - 1):
                if i < len(starts):
                    model.param_array[:] = starts[i]
                    model.update_model(True)
                else:
                    model.randomize()
                try:
                    model.optimize()
                except np.linalg.LinAlgError:  # a random start with a singular kernel matrix: skip it
                    continue
                optima.append((float(model.objective_function()), model.param_array.copy()))
            if not optima:
                raise ParameterError("GP fit failed from every start (kernel matrix not positive definite)")
            model.param_array[:] = min(optima, key=lambda o: o[0])[1]
            model.update_model(True)
        return cls(model, lower, upper, shift, scale)

    def conditioned_on(self, x: np.ndarray, y: np.ndarray) -> "ObjectiveGP":
        """The same GP (hyperparameters and standardisation kept, no refit) conditioned on *latent* values ``y`` at
        ``x``: the fantasised observations get a negligible noise variance (GPy's heteroscedastic Gaussian
        likelihood), the real ones keep σ_n². With ``y`` = the GP mean (Kriging believer) the mean is unchanged
        and the latent variance at ``x`` drops to ~0, so a batch does not pick the same design twice; conditioning
        with noise σ_n² left it almost unchanged when σ_n exceeded the latent std (seen on noisy ZDT1).
        """
        z = np.vstack([self.model.X, self._unit(x)])
        ys = np.vstack([self.model.Y, ((np.asarray(y, dtype=float).ravel() - self.shift) / self.scale)[:, None]])
        model = GPy.models.GPHeteroscedasticRegression(z, ys, kernel=self.model.kern.copy())
        n = self.model.X.shape[0]
        noise = np.full(z.shape[0], _FANTASY_NOISE)
        noise[:n] = self.model.likelihood.variance.values.ravel()[0]
        model.het_Gauss.variance[:] = noise[:, None]
        model.het_Gauss.variance.fix(warning=False)
        return ObjectiveGP(model, self.lower, self.upper, self.shift, self.scale)

    def _unit(self, x: np.ndarray) -> np.ndarray:
        return (np.atleast_2d(np.asarray(x, dtype=float)) - self.lower) / (self.upper - self.lower)

    def predict(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Latent posterior mean and standard deviation (m,) each at designs ``x`` (m, d)."""
        with _single_threaded():
            mean, var = self.model.predict_noiseless(self._unit(x))
        var = np.maximum(var[:, 0], _VARIANCE_FLOOR)
        return self.shift + self.scale * mean[:, 0], self.scale * np.sqrt(var)

    def predict_with_gradient(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Latent mean, standard deviation (m,) and their gradients (m, d) with respect to physical ``x``."""
        z = self._unit(x)
        with _single_threaded():
            mean, var = self.model.predict_noiseless(z)
            dmean, dvar = self.model.predictive_gradients(z)
        var = var[:, 0]
        floored = var <= _VARIANCE_FLOOR
        std = np.sqrt(np.maximum(var, _VARIANCE_FLOOR))
        dstd = np.where(floored[:, None], 0.0, dvar / (2.0 * std[:, None]))
        to_x = self.scale / (self.upper - self.lower)  # chain rule through z and the output standardisation
        return self.shift + self.scale * mean[:, 0], self.scale * std, dmean[:, :, 0] * to_x, dstd * to_x

    def posterior_draws(self, x: np.ndarray, n_draws: int, rng: np.random.Generator) -> np.ndarray:
        """``n_draws`` joint draws (n_draws, m) of the latent objective at designs ``x`` (m, d)."""
        with _single_threaded():
            mean, cov = self.model.predict_noiseless(self._unit(x), full_cov=True)
            draws = rng.multivariate_normal(mean[:, 0], cov, size=n_draws, method="eigh", check_valid="ignore")
        return self.shift + self.scale * draws

    @property
    def noise_variance(self) -> float:
        """Learned observation-noise variance σ_n² (of the real observations) in squared objective units."""
        return float(self.model.likelihood.variance.values.ravel()[0]) * self.scale**2

    def hyperparameters(self) -> dict[str, np.ndarray | float]:
        """Length scales (d,) in design units, signal and noise variances in squared objective units."""
        kern = self.model.kern
        return {"lengthscale": np.asarray(kern.lengthscale, dtype=float) * (self.upper - self.lower),
                "signal_variance": float(kern.variance.values[0]) * self.scale**2,
                "noise_variance": self.noise_variance}
