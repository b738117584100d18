"""What the two MCMC sampler stages (``emcee_sampler``, ``mh_sampler``) share: inputs, parameters, the posterior model
and the assembly of the posterior Dataset. A subclass implements only ``_sample_runs`` (the independent chains).

Inputs: a fitted surrogate (any kind, :func:`~spflow.plugins.surrogates.contract.load_surrogate`), the observed data
on the simulator grid (``observations`` stage) and the parameter space that gives the prior: uniform on its box
(Eq. 4.2), or the marginals it records (``priors`` stage with ``distribution="truncated_normal"``;
:mod:`.parameter_prior`). The box must lie inside the surrogate's training box. The prior of every parameter is
printed (``verbose``) and recorded in the output: attrs ``prior`` (one ``name ~ law`` line per parameter) and
``prior_note`` (what was assumed), and the variables ``distribution`` / ``distribution_parameters`` along ``param``. The budget follows the thesis (§4.6): ``samples`` = 10^5 posterior
evaluations per chain, the first ``burn`` = 20 000 discarded, every ``thin`` = 5th kept — 16 000 draws per chain.
Independent chains are seeded from ``seed`` by ``numpy.random.SeedSequence.spawn``, so a run is reproducible whatever
the worker count.
"""

from __future__ import annotations

import sys

import numpy as np
import xarray as xr

from spflow.core.errors import ParameterError
from spflow.core.params import Param
from spflow.core.stage import Stage, StageContext
from spflow.plugins.design.schemas import SPACE
from spflow.plugins.observations import OBSERVATIONS
from spflow.plugins.surrogates.contract import SURROGATE, Surrogate, load_surrogate

from .aligned_data import align
from .likelihood import NOISE_MODES, PosteriorModel
from .parameter_prior import ParameterPrior
from .posterior import POSTERIOR, posterior_dataset

__all__ = ["SamplerStage", "ChainResult"]

#: Relative slack when checking that the prior box lies inside the surrogate's box.
_BOX_TOL = 1e-9


class ChainResult(dict):
    """One chain's output: ``x`` (walker, draw, ndim), ``log_posterior`` and ``log_likelihood`` (walker, draw) and
    ``acceptance`` (walker,); a single MH chain has one walker."""


class SamplerStage(Stage):
    """Base of the MCMC stages; subclasses set ``name``/``description``, extra ``params`` and ``_sample_runs``."""

    inputs = {"surrogate": SURROGATE, "observations": OBSERVATIONS, "space": SPACE}
    output = POSTERIOR
    common_params = {
        "experiments": Param(list, ["BCF1"], doc="experiments whose data train the posterior (thesis: BCF1)"),
        "variables": Param(list, ["dp", "oil_cut"], choices=["dp", "oil_cut", "recovery"],
                           doc="QoIs, one noise level per variable and experiment (thesis: dp and oil cut)"),
        "noise": Param(str, "jeffreys_marginal", choices=list(NOISE_MODES),
                       doc="per-QoI noise: Jeffreys prior integrated out, sampled (log sigma), or known"),
        "sigma": Param(list, [], bounds=(0.0, None), doc="known noise std per block (noise='known'), block units"),
        "surrogate_variance": Param(bool, True, doc="add the surrogate's error variance to the noise variance"),
        "samples": Param(int, 100_000, bounds=(10, 10**8), doc="posterior evaluations per chain (thesis 1e5)"),
        "burn": Param(int, 20_000, bounds=(0, 10**8), doc="evaluations discarded per chain (thesis 20 000)"),
        "thin": Param(int, 5, bounds=(1, 10**6), doc="keep every thin-th step (thesis 5)"),
        "chains": Param(int, 4, bounds=(1, 64), doc="independent chains"),
        "seed": Param(int, 0, bounds=(0, 2**32 - 1), doc="random seed"),
    }

    def __init__(self, **params):
        super().__init__(**params)
        p = self.params
        if p["burn"] >= p["samples"]:
            raise ParameterError(f"stage {self.name!r}: burn = {p['burn']} must be smaller than samples = "
                                 f"{p['samples']}")
        if not p["experiments"] or not p["variables"]:
            raise ParameterError(f"stage {self.name!r}: experiments and variables must be non-empty lists")
        blocks = len(p["experiments"]) * len(p["variables"])
        if p["noise"] == "known" and (len(p["sigma"]) != blocks or min(p["sigma"], default=0) <= 0):
            raise ParameterError(f"stage {self.name!r} parameter 'sigma': noise='known' needs {blocks} positive "
                                 f"values (one per variable x experiment), got {p['sigma']}")
        self._check_budget()

    def _check_budget(self) -> None:
        """Subclass hook: raise ParameterError when the budget leaves no draws."""

    def pairs(self) -> list[tuple[str, str]]:
        return [(v, e) for e in self.params["experiments"] for v in self.params["variables"]]

    def model(self, surrogate: Surrogate, observations: xr.Dataset, space: xr.Dataset) -> PosteriorModel:
        """The posterior model in the surrogate's parameter order, with the space's prior (:mod:`.parameter_prior`);
        raises before any work if the prior box is not inside the surrogate's box or a block has no data."""
        names = [str(n) for n in space["param"].values]
        if sorted(names) != sorted(surrogate.names):
            raise ParameterError(f"stage {self.name!r}: space parameters {names} differ from the surrogate's "
                                 f"{surrogate.names}")
        box = space.sel(param=surrogate.names)
        lower, upper = box["lower"].values.astype(float), box["upper"].values.astype(float)
        slack = _BOX_TOL * (surrogate.upper - surrogate.lower)
        outside = [n for n, lo, hi, slo, shi, tol in zip(surrogate.names, lower, upper, surrogate.lower,
                                                         surrogate.upper, slack) if lo < slo - tol or hi > shi + tol]
        if outside:
            n = outside[0]
            k = surrogate.names.index(n)
            raise ParameterError(f"stage {self.name!r}: prior range of {n} [{lower[k]:g}, {upper[k]:g}] must lie "
                                 f"inside the surrogate's training range [{surrogate.lower[k]:g}, "
                                 f"{surrogate.upper[k]:g}]")
        prior = ParameterPrior.of_space(box, f"stage {self.name!r}")
        aligned = align(surrogate.outputs, observations, self.pairs())
        return PosteriorModel(surrogate, aligned, self.pairs(), lower, upper, noise=self.params["noise"],
                              sigma=tuple(self.params["sigma"]), surrogate_variance=self.params["surrogate_variance"],
                              prior=prior)

    def _check_model(self, model: PosteriorModel) -> None:
        """Subclass hook: raise ParameterError when the sampler cannot handle the model (before any sampling)."""

    def _sample_runs(self, ctx: StageContext, model: PosteriorModel,
                     seeds: list[np.random.SeedSequence]) -> list[ChainResult]:
        """One :class:`ChainResult` per seed (independent runs)."""
        raise NotImplementedError

    def _chain_coords(self, results: list[ChainResult]) -> dict:
        return {}

    def _attrs(self, results: list[ChainResult]) -> dict:
        return {}

    def run(self, ctx: StageContext, surrogate: xr.Dataset, observations: xr.Dataset, space: xr.Dataset) -> xr.Dataset:
        sur = load_surrogate(surrogate)
        model = self.model(sur, observations, space)
        self._check_model(model)
        if ctx.verbose:
            note = f" ({model.prior.note})" if model.prior.note else ""
            print(f"[{ctx.node}] prior{note}:\n  " + model.prior.describe().replace("\n", "\n  "), file=sys.stderr,
                  flush=True)
        *seeds, noise_seed = np.random.SeedSequence(self.params["seed"]).spawn(self.params["chains"] + 1)
        results = self._sample_runs(ctx, model, seeds)
        x = np.concatenate([r["x"] for r in results])  # (chain, draw, ndim): walkers of every run
        chains, draws = x.shape[:2]
        sigma = model.noise_draws(x.reshape(chains * draws, -1), np.random.default_rng(noise_seed))
        sigma = sigma.reshape(chains, draws, -1)
        space = space.sel(param=sur.names)
        units = [sur.outputs.units.get(v, "1") for v, _ in model.pairs]
        attrs = {"sampler": self.name, "noise": self.params["noise"], "surrogate": str(surrogate.attrs["surrogate"]),
                 "surrogate_variance": int(self.params["surrogate_variance"]), "samples": self.params["samples"],
                 "burn": self.params["burn"], "thin": self.params["thin"], "independent_chains": self.params["chains"],
                 "seed": self.params["seed"], "prior": model.prior.describe(), "prior_note": model.prior.note,
                 **self._attrs(results)}
        return posterior_dataset(
            x[..., : model.n_theta], sigma, np.concatenate([r["log_likelihood"] for r in results]),
            np.concatenate([r["log_posterior"] for r in results]), np.concatenate([r["acceptance"] for r in results]),
            space=space, pairs=model.pairs, points=model.points(), units=units, attrs=attrs,
            chain_coords=self._chain_coords(results), prior=model.prior.variables())
