"""The posterior of thesis §4.6: the prior of the parameters (uniform on the box, Eq. 4.2, or the space's marginals:
:mod:`.parameter_prior`) times a Gaussian likelihood per QoI block (Eq. 4.3) with the forward model replaced by a
surrogate (Eq. 4.5).

A block is one (variable, experiment) pair — e.g. pressure drop of BCF1 on the 0.1 PV grid — with its own noise
level σ_i. Three treatments of σ_i (``noise``):

* ``"jeffreys_marginal"`` (default): σ_i under Jeffreys' prior (Eq. 4.4) integrated out (:mod:`.jeffreys`);
* ``"jeffreys_sampled"``: log σ_i are extra MCMC coordinates with the same prior (flat in log σ when v ≡ 0);
* ``"known"``: σ_i given.

The surrogate's own error variance v_k(θ) (``Surrogate.predict``'s variance: the PCE's LOO error, the Kriging
variance) adds to the measurement variance point by point, d_k ~ N(f_k(θ), σ_i² + v_k(θ)), when
``surrogate_variance`` is on. How that enters the marginal (and why the plain 1/σ prior then fails) is documented in
:mod:`.jeffreys`.

Everything is vectorised over rows of parameter vectors (emcee walkers, independent MH chains): one surrogate call per
batch, only for the rows inside the box. It is the MCMC hot path (10^5 calls of one row per MH chain), so shapes are
checked once at construction, each block's prediction columns are a precomputed slice where consecutive, the
surrogate variance is clipped once per call, and blocks whose variance is identically zero (``surrogate_variance``
off, or rows with v ≡ 0) use the closed form without building a zero array.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from spflow.core.errors import ParameterError
from spflow.plugins.surrogates.contract import Surrogate

from .aligned_data import AlignedData
from .parameter_prior import ParameterPrior

__all__ = ["NOISE_MODES", "PosteriorModel"]

NOISE_MODES = ("jeffreys_marginal", "jeffreys_sampled", "known")
_LOG_2PI = np.log(2.0 * np.pi)


@dataclass
class PosteriorModel:
    """log posterior of θ (and of log σ_i when sampled) given a surrogate and aligned observations.

    ``lower``/``upper`` is the prior box in the surrogate's parameter order; ``pairs`` the blocks; ``sigma`` the known
    noise levels (``noise="known"`` only, one per block, in the block's units); ``prior`` the parameters' marginals
    (:class:`.ParameterPrior`, in the surrogate's order, supports = the box; None: uniform on the box, Eq. 4.2).
    """

    surrogate: Surrogate
    aligned: AlignedData
    pairs: list[tuple[str, str]]
    lower: np.ndarray
    upper: np.ndarray
    noise: str = "jeffreys_marginal"
    sigma: tuple[float, ...] = ()
    surrogate_variance: bool = True
    prior: ParameterPrior | None = None

    def __post_init__(self):
        if self.noise not in NOISE_MODES:
            raise ParameterError(f"noise must be one of {NOISE_MODES}, got {self.noise!r}")
        if self.noise == "known":
            if len(self.sigma) != len(self.pairs) or not all(np.isfinite(s) and s > 0 for s in self.sigma):
                raise ParameterError(f"noise='known' needs sigma = one positive value per block {self.pairs}, "
                                     f"got {list(self.sigma)}")
        self.lower = np.asarray(self.lower, dtype=float)
        self.upper = np.asarray(self.upper, dtype=float)
        self.columns = [np.asarray(self.aligned.blocks[p][0], dtype=np.intp) for p in self.pairs]
        self.observed = [np.asarray(self.aligned.blocks[p][1], dtype=float) for p in self.pairs]
        if self.lower.shape != (len(self.surrogate.names),) or self.upper.shape != self.lower.shape:
            raise ParameterError(f"prior box: lower and upper need one value per surrogate parameter "
                                 f"{self.surrogate.names}, got shapes {self.lower.shape} and {self.upper.shape}")
        for (variable, experiment), cols, obs in zip(self.pairs, self.columns, self.observed):
            if cols.shape != obs.shape or cols.ndim != 1 or not cols.size:
                raise ParameterError(f"block {variable}/{experiment}: column numbers {cols.shape} and observations "
                                     f"{obs.shape} must be equal-length non-empty vectors")
        # each block's prediction columns once: a slice (a view, no copy per call) where they are consecutive
        self._take = [slice(int(c[0]), int(c[-1]) + 1) if np.array_equal(c, np.arange(c[0], c[-1] + 1)) else c
                      for c in self.columns]
        if self.prior is None:
            self.prior = ParameterPrior.box(self.surrogate.names, self.lower, self.upper)
        elif not (np.array_equal(self.prior.lower, self.lower) and np.array_equal(self.prior.upper, self.upper)):
            raise ParameterError(f"prior: the supports of the marginals {self.prior.describe()!r} must be the box "
                                 f"lower = {self.lower.tolist()}, upper = {self.upper.tolist()}")

    @property
    def n_theta(self) -> int:
        return self.lower.size

    @property
    def ndim(self) -> int:
        """Sampled coordinates: θ, then log σ_i per block when ``noise="jeffreys_sampled"``."""
        return self.n_theta + (len(self.pairs) if self.noise == "jeffreys_sampled" else 0)

    def points(self) -> list[int]:
        return [obs.size for obs in self.observed]

    def inside(self, theta: np.ndarray) -> np.ndarray:
        return np.all((theta >= self.lower) & (theta <= self.upper), axis=1)

    def _blocks(self, theta: np.ndarray):
        """Residuals r and surrogate variances v (rows, n_i), v C-contiguous and >= 0, of every block at θ (rows
        inside the box); v is ``None`` when the surrogate variance is left out (v ≡ 0)."""
        mean, var = self.surrogate.predict(theta)
        var = np.maximum(var, 0.0) if self.surrogate_variance else None
        for take, obs in zip(self._take, self.observed):
            yield obs - mean[:, take], None if var is None else np.ascontiguousarray(var[:, take])

    def evaluate(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(log posterior, log likelihood), each (rows,), at coordinates ``x`` (rows, ndim); −inf outside the box (the
        supports of the prior's marginals)."""
        from . import jeffreys  # numba kernels: compiled when a posterior is evaluated, not when spflow lists stages

        x = np.atleast_2d(np.asarray(x, dtype=float))
        log_post = np.full(x.shape[0], -np.inf)
        log_lik = np.full(x.shape[0], -np.inf)
        theta = x[:, : self.n_theta]
        ok = np.flatnonzero(self.inside(theta))
        if not ok.size:
            return log_post, log_lik
        inner = theta if ok.size == x.shape[0] else theta[ok]
        lik = np.zeros(ok.size)
        prior = self.prior.log_density(inner)
        for i, (r, v) in enumerate(self._blocks(inner)):
            if self.noise == "jeffreys_marginal":
                lik += jeffreys.log_marginal_checked(r, v)
                continue
            if self.noise == "known":
                sigma = np.full(ok.size, self.sigma[i])
            else:
                sigma = np.exp(x[ok, self.n_theta + i])
                if v is not None:  # the prior in log σ is flat (exactly 0) when v ≡ 0
                    prior += jeffreys.log_sigma_prior(sigma, v)
            total = sigma[:, None] ** 2 + (0.0 if v is None else v)
            lik += -0.5 * np.sum(_LOG_2PI + np.log(total) + r * r / total, axis=1)
        log_lik[ok] = lik
        log_post[ok] = lik + prior
        return log_post, log_lik

    def __call__(self, x: np.ndarray) -> np.ndarray:
        """emcee's vectorised log-probability: rows of (log posterior, log likelihood) — the second is a blob."""
        return np.column_stack(self.evaluate(x))

    def pointwise_log_likelihood(self, theta: np.ndarray, sigma: np.ndarray) -> np.ndarray:
        """log N(d_k; f_k(θ), σ_i² + v_k(θ)) of every observation k (rows, n_observations) at joint draws of θ
        (rows, n_theta) and σ (rows, n_blocks): Eq. 4.3 term by term, observations in block order (``pairs``).

        Summed over k it is the log likelihood that ``evaluate`` records for known or sampled σ_i; with σ_i
        integrated out (``jeffreys_marginal``) ``evaluate`` records the marginal, which does not split into terms
        per observation, and this is the likelihood conditional on the draw's σ_i from p(σ_i | θ, d)
        (:meth:`noise_draws`) — the pointwise form that PSIS-LOO needs."""
        theta = np.atleast_2d(np.asarray(theta, dtype=float))
        sigma = np.atleast_2d(np.asarray(sigma, dtype=float))
        if sigma.shape != (theta.shape[0], len(self.pairs)):
            raise ParameterError(f"pointwise log likelihood: sigma needs shape ({theta.shape[0]}, {len(self.pairs)}) "
                                 f"(rows, blocks {self.pairs}), got {sigma.shape}")
        terms = []
        for i, (r, v) in enumerate(self._blocks(theta)):
            total = sigma[:, i, None] ** 2 + (0.0 if v is None else v)
            terms.append(-0.5 * (_LOG_2PI + np.log(total) + r * r / total))
        return np.concatenate(terms, axis=1)

    def predictive_draws(self, theta: np.ndarray, sigma: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        """New observations (rows, n_observations) drawn from Eq. 4.3 with the surrogate for the forward model:
        d_k ~ N(f_k(θ), σ_i² + v_k(θ)) at each joint draw of θ and σ, observations in block order."""
        theta = np.atleast_2d(np.asarray(theta, dtype=float))
        out = []
        for i, (r, v) in enumerate(self._blocks(theta)):
            mean = self.observed[i] - r
            sd = np.sqrt(sigma[:, i, None] ** 2 + (0.0 if v is None else v))
            out.append(mean + sd * rng.standard_normal(mean.shape))
        return np.concatenate(out, axis=1)

    def noise_draws(self, x: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        """σ_i (rows, n_blocks) for each coordinate row: read off when sampled or known, drawn from p(σ_i | θ, d)
        when marginalised (exact joint draws of (θ, σ))."""
        x = np.atleast_2d(np.asarray(x, dtype=float))
        if self.noise == "jeffreys_sampled":
            return np.exp(x[:, self.n_theta:])
        if self.noise == "known":
            return np.tile(np.asarray(self.sigma, dtype=float), (x.shape[0], 1))
        from . import jeffreys

        out = np.empty((x.shape[0], len(self.pairs)))
        for i, (r, v) in enumerate(self._blocks(x[:, : self.n_theta])):
            out[:, i] = jeffreys.sample_sigma(r, 0.0 if v is None else v, rng)
        return out

    def initial_log_sigma(self, theta: np.ndarray) -> np.ndarray:
        """Profile values log sqrt(S_i/n_i) at θ (rows, n_blocks): a starting point for sampled noise levels."""
        return np.column_stack([0.5 * np.log(np.mean(r * r, axis=1) + (0.0 if v is None else np.mean(v, axis=1))
                                             + 1e-300) for r, v in self._blocks(theta)])
