"""The ``mh_sampler`` stage: random-walk Metropolis–Hastings, the thesis's sampler (PyMC ``Metropolis``, §4.6).

Each chain is one random walk with its own Gaussian proposal; the accept/reject step is emcee's
:class:`emcee.moves.MHMove`, whose walkers accept or reject independently, so the ``chains`` independent chains run in
lockstep as the walkers of one emcee sampler (one vectorised likelihood call per step for all of them) and the two
sampler stages share emcee's bookkeeping. The proposal is tuned during burn-in
only, then frozen, so the kept draws come from a time-homogeneous Metropolis–Hastings chain:

* it starts as independent steps of ``initial_scale`` × the prior box width per parameter;
* every ``tune_interval`` steps its scale λ is multiplied by PyMC's rule for the block's acceptance rate (× 0.1 below
  0.001, × 0.5 below 0.05, × 0.9 below 0.2, × 1.1 above 0.5, × 2 above 0.75, × 10 above 0.95);
* with ``adapt_covariance`` its shape becomes 2.38²/d times the covariance of the second half of the chain so far
  (Haario et al. 2001, adaptive Metropolis), λ reset to 1 at the first such update.

Budget as the thesis: ``samples`` steps per chain, ``burn`` discarded, every ``thin``-th kept.
"""

from __future__ import annotations

import numpy as np

from spflow.core.errors import ParameterError
from spflow.core.params import Param
from spflow.core.stage import StageContext

from .emcee_sampler import initial_points
from .likelihood import PosteriorModel
from .mcmc_stage import ChainResult, SamplerStage

__all__ = ["MHSampler", "GaussianProposal", "pymc_tune_factor"]


def pymc_tune_factor(acceptance: float) -> float:
    """PyMC's ``Metropolis`` step-size update for the acceptance rate of the last tuning interval."""
    for limit, factor in ((0.001, 0.1), (0.05, 0.5), (0.2, 0.9)):
        if acceptance < limit:
            return factor
    for limit, factor in ((0.95, 10.0), (0.75, 2.0), (0.5, 1.1)):
        if acceptance > limit:
            return factor
    return 1.0


class GaussianProposal:
    """Symmetric random-walk proposal for :class:`emcee.moves.MHMove`, one per chain (walker):
    x'_c = x_c + λ_c L_c z_c with z_c ~ N(0, I). Chains do not share anything, so they stay independent."""

    def __init__(self, chol: np.ndarray):
        self.chol = np.array(chol, dtype=float)  # (chain, d, d)
        self.scale = np.ones(self.chol.shape[0])

    def __call__(self, coords: np.ndarray, random) -> tuple[np.ndarray, np.ndarray]:
        step = np.einsum("cij,cj->ci", self.chol, random.standard_normal(coords.shape))
        return coords + self.scale[:, None] * step, np.zeros(coords.shape[0])


class MHSampler(SamplerStage):
    name = "mh_sampler"
    # 4: the prior is the space's marginals (uniform: the box, unchanged draws; issue #24); every unit in UDUNITS form (issue 23)
    version = "4"
    description = "adaptive random-walk Metropolis-Hastings on a surrogate posterior (thesis §4.6, PyMC-like)"
    params = SamplerStage.common_params | {
        "tune_interval": Param(int, 500, bounds=(10, 10**7), doc="burn-in steps between proposal updates"),
        "initial_scale": Param(float, 0.02, bounds=(1e-8, 1.0), doc="first step size as a fraction of the box width"),
        "adapt_covariance": Param(bool, True, doc="proposal shape from the chain's covariance during burn-in"),
        "init": Param(str, "prior", choices=["prior", "best"], doc="chain start: a prior draw or the best of them"),
        "init_draws": Param(int, 4096, bounds=(1, 10**7), doc="uniform draws screened by init='best'"),
    }

    def _check_budget(self) -> None:
        p = self.params
        if (p["samples"] - p["burn"]) // p["thin"] < 1:
            raise ParameterError(f"stage {self.name!r}: samples - burn = {p['samples'] - p['burn']} must be at least "
                                 f"thin = {p['thin']}")

    def _sample_runs(self, ctx: StageContext, model: PosteriorModel,
                     seeds: list[np.random.SeedSequence]) -> list[ChainResult]:
        """All chains in lockstep as the walkers of one emcee sampler (one vectorised likelihood call per step)."""
        p = self.params
        rngs = [np.random.default_rng(s) for s in seeds]
        start = np.concatenate([initial_points(model, 1, p["init"], p["init_draws"], r) for r in rngs])
        chains = len(seeds)
        width = np.concatenate([model.upper - model.lower, np.ones(model.ndim - model.n_theta)])
        proposal = GaussianProposal(np.tile(np.diag(p["initial_scale"] * width), (chains, 1, 1)))
        import emcee

        sampler = emcee.EnsembleSampler(chains, model.ndim, model, moves=emcee.moves.MHMove(proposal), vectorize=True,
                                        blobs_dtype=float)
        sampler.random_state = np.random.RandomState(int(rngs[0].integers(2**32))).get_state()
        state, done, adapted = start, 0, np.zeros(chains, dtype=bool)
        kept = (p["samples"] - p["burn"]) // p["thin"]
        steps = p["burn"] + kept * p["thin"]
        ctx.report_progress(0, steps, "steps")
        for n in np.diff(np.r_[0:p["burn"]:p["tune_interval"], p["burn"]]):
            accepted = sampler.acceptance_fraction * sampler.iteration if done else np.zeros(chains)
            state = sampler.run_mcmc(state, n, skip_initial_state_check=True)
            done += n
            ctx.report_progress(done, steps, "steps")
            proposal.scale *= [pymc_tune_factor(r) for r in (sampler.acceptance_fraction * done - accepted) / n]
            history = sampler.get_chain()[done // 2:]
            for c in range(chains) if p["adapt_covariance"] and len(history) > 2 * model.ndim else ():
                if np.ptp(history[:, c], axis=0).all():
                    cov = np.cov(history[:, c], rowvar=False) * 2.38**2 / model.ndim + np.diag((1e-10 * width) ** 2)
                    proposal.chol[c] = np.linalg.cholesky(cov)
                    proposal.scale[c] = proposal.scale[c] if adapted[c] else 1.0
                    adapted[c] = True
        sampler.reset()
        # what run_mcmc does, reporting each kept step
        for k, _ in enumerate(sampler.sample(state, iterations=kept, thin_by=p["thin"], skip_initial_state_check=True),
                              1):
            ctx.report_progress(done + k * p["thin"], steps, "steps")
        x, log_post, log_lik = sampler.get_chain(), sampler.get_log_prob(), sampler.get_blobs()
        return [ChainResult(x=x[None, :, c], log_posterior=log_post[None, :, c], log_likelihood=log_lik[None, :, c],
                            acceptance=sampler.acceptance_fraction[c:c + 1]) for c in range(chains)]

    def _attrs(self, results: list[ChainResult]) -> dict:
        return {"tune_interval": self.params["tune_interval"], "initial_scale": self.params["initial_scale"],
                "adapt_covariance": int(self.params["adapt_covariance"]), "init": self.params["init"]}
