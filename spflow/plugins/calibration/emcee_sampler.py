"""The ``emcee_sampler`` stage (default sampler of the chapter-4 pipeline): emcee's affine-invariant ensemble sampler on
the surrogate posterior of thesis §4.6.

Each of ``chains`` independent runs moves ``walkers`` walkers (default: twice the number of sampled dimensions, the
fewest emcee's ensemble moves accept — for a fixed budget of evaluations fewer walkers make longer chains); the
likelihood of all walkers of a run is one vectorised surrogate call (``vectorize=True``). The thesis's budget is
counted in posterior evaluations per run: ``samples // walkers`` iterations, the first ``burn // walkers``
discarded, then every ``thin``-th iteration kept — with the defaults (10^5, 20 000, 5) and 18 walkers (9 parameters)
888 draws per walker, about 16 000 per run as in the thesis. Following ArviZ's ``from_emcee`` convention every
walker is a ``chain`` of the output (coordinates ``chain_run`` and ``chain_walker`` say which run and walker);
walkers of one run are not independent, so R-hat across them is a heuristic — across runs it is a real check.

Moves: ``de_snooker`` (default: 80 % differential evolution, 20 % snooker, emcee's suggestion for multimodal targets,
emcee's documentation on moves, Foreman-Mackey et al. 2013; ter Braak & Vrugt 2008) or ``stretch`` (emcee's own
default, a = 2). On the 9-parameter chapter-4 posterior of
a clean twin the stretch move needed about 3x more evaluations per effective sample (τ ≈ 40 vs 15 kept draws per
walker at 18 walkers) and left R-hat near 1.1 within the thesis budget; see ``docs/calibration.md``.

Start: ``prior`` draws walkers from the prior (uniform in the box, or the space's marginals: :mod:`.parameter_prior`),
so every walker starts inside the support; ``best`` takes the ``walkers`` most probable of ``init_draws`` prior draws
(cheap on a surrogate).
"""

from __future__ import annotations

import numpy as np

from spflow.core.errors import ParameterError
from spflow.core.params import Param
from spflow.core.stage import StageContext

from .likelihood import PosteriorModel
from .mcmc_stage import ChainResult, SamplerStage

__all__ = ["EmceeSampler", "initial_points"]

_MOVES = {
    "stretch": lambda moves: moves.StretchMove(),
    "de_snooker": lambda moves: [(moves.DEMove(), 0.8), (moves.DESnookerMove(), 0.2)],
}


def initial_points(model: PosteriorModel, count: int, how: str, draws: int, rng: np.random.Generator) -> np.ndarray:
    """``count`` starting points (count, ndim): prior draws (``prior``; uniform in the box for a uniform prior) or the
    most probable ``count`` of ``draws`` prior draws (``best``); sampled log σ_i start at their profile values with a
    small jitter."""
    pool = model.prior.sample((max(count, draws) if how == "best" else count,), rng)
    if how == "best":
        log_post = np.concatenate([model.evaluate(chunk)[0] for chunk in np.array_split(pool, -(-len(pool) // 4096))])
        pool = pool[np.argsort(-log_post)[:count]]
    if model.ndim > model.n_theta:
        pool = np.column_stack([pool, model.initial_log_sigma(pool) + rng.normal(0.0, 0.05, (count, model.ndim -
                                                                                                 model.n_theta))])
    return pool


class EmceeSampler(SamplerStage):
    name = "emcee_sampler"
    # 4: the prior is the space's marginals (uniform: the box, unchanged draws; issue #24); every unit in UDUNITS form (issue 23)
    version = "4"
    description = "emcee ensemble MCMC on a surrogate posterior (thesis §4.6, Eqs. 4.1-4.5)"
    params = SamplerStage.common_params | {
        "walkers": Param(int, 0, bounds=(0, 4096), doc="walkers per run, >= 2 x sampled dimensions (0: exactly that)"),
        "moves": Param(str, "de_snooker", choices=sorted(_MOVES), doc="emcee moves"),
        "init": Param(str, "prior", choices=["prior", "best"], doc="walker start: prior draws or the best of them"),
        "init_draws": Param(int, 4096, bounds=(1, 10**7), doc="uniform draws screened by init='best'"),
    }

    def walkers(self, model: PosteriorModel) -> int:
        return self.params["walkers"] or 2 * model.ndim

    def _iterations(self, walkers: int) -> tuple[int, int]:
        """(burn-in iterations, kept draws per walker)."""
        p = self.params
        return p["burn"] // walkers, (p["samples"] - p["burn"]) // (walkers * p["thin"])

    def _check_budget(self, walkers: int | None = None) -> None:
        p = self.params
        walkers = walkers or p["walkers"]
        if walkers and self._iterations(walkers)[1] < 1:
            raise ParameterError(f"stage {self.name!r}: samples - burn = {p['samples'] - p['burn']} leaves no draw "
                                 f"for {walkers} walkers thinned by {p['thin']}; need >= walkers x thin")

    def _check_model(self, model: PosteriorModel) -> None:
        walkers = self.walkers(model)
        if walkers < 2 * model.ndim:
            raise ParameterError(f"stage {self.name!r} parameter 'walkers' = {walkers} must be at least 2 x "
                                 f"{model.ndim} sampled dimensions for emcee's ensemble moves")
        self._check_budget(walkers)

    def _sample_runs(self, ctx: StageContext, model: PosteriorModel,
                     seeds: list[np.random.SeedSequence]) -> list[ChainResult]:
        """Independent runs in parallel with the node's joblib budget. With one worker they run in this process, one
        after another, and report every ensemble step (burn-in and kept, times the thinning) of every run; with
        several, each runs in a worker and the progress is the runs finished."""
        if ctx.n_jobs == 1:
            burn, keep = self._iterations(self.walkers(model))
            per_run = burn + keep * self.params["thin"]
            total = per_run * len(seeds)
            ctx.report_progress(0, total, "steps")
            return [self._sample_run(model, s, lambda k, r=r: ctx.report_progress(r * per_run + k, total, "steps"))
                    for r, s in enumerate(seeds)]
        from joblib import delayed

        return ctx.parallel()(delayed(self._sample_run)(model, s) for s in ctx.progress(seeds, what="runs"))

    def _sample_run(self, model: PosteriorModel, seed: np.random.SeedSequence, step=None) -> ChainResult:
        """One run of ``walkers`` walkers; ``step(k)`` (optional) is told after each ensemble step that ``k`` steps of
        the run are done (the sampler's own iteration, as ``run_mcmc`` does it)."""
        p, walkers = self.params, self.walkers(model)
        rng = np.random.default_rng(seed)
        burn, keep = self._iterations(walkers)
        start = initial_points(model, walkers, p["init"], p["init_draws"], rng)
        import emcee

        sampler = emcee.EnsembleSampler(walkers, model.ndim, model, moves=_MOVES[p["moves"]](emcee.moves),
                                        vectorize=True,
                                        blobs_dtype=float)
        sampler.random_state = np.random.RandomState(int(rng.integers(2**32))).get_state()
        state = start
        for k, state in enumerate(sampler.sample(start, iterations=burn), 1):
            if step is not None:
                step(k)
        sampler.reset()
        for k, _ in enumerate(sampler.sample(state, iterations=keep, thin_by=p["thin"]), 1):
            if step is not None:
                step(burn + k * p["thin"])
        return ChainResult(x=np.swapaxes(sampler.get_chain(), 0, 1), log_posterior=sampler.get_log_prob().T,
                           log_likelihood=sampler.get_blobs().T, acceptance=sampler.acceptance_fraction)

    def _chain_coords(self, results: list[ChainResult]) -> dict:
        walkers = results[0]["x"].shape[0]
        return {"chain_run": ("chain", np.repeat(np.arange(len(results)), walkers),
                              {"units": "1", "long_name": "independent run the walker belongs to"}),
                "chain_walker": ("chain", np.tile(np.arange(walkers), len(results)),
                                 {"units": "1", "long_name": "walker number within its run"})}

    def _attrs(self, results: list[ChainResult]) -> dict:
        walkers = results[0]["x"].shape[0]
        return {"walkers": walkers, "moves": self.params["moves"], "init": self.params["init"],
                "iterations_burn": self._iterations(walkers)[0], "draws_per_walker": results[0]["x"].shape[1]}
