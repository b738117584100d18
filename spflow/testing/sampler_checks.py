"""``check_sampler``: the conformance checks of an MCMC sampler stage (built-in ``emcee_sampler``/``mh_sampler`` or a
plugin's), on the Gaussian target of :mod:`.gaussian_target` whose posterior mean and covariance are known.

A sampler is a stage with the ports ``surrogate``, ``observations`` and ``space`` and the parameters of
:class:`~spflow.plugins.calibration.mcmc_stage.SamplerStage` (a subclass implementing ``_sample_runs`` has them),
returning the ``POSTERIOR`` Dataset.

``declaration``
    the ports and the shared parameters (``experiments``, ``variables``, ``noise``, ``sigma``,
    ``surrogate_variance``, ``seed``) are declared.
``runs``
    on the target it returns a Dataset matching ``POSTERIOR`` with finite log posteriors and acceptance in [0, 1].
``seed_determinism``
    the same seed gives identical draws; another seed gives other draws.
``prior_support``
    every draw lies in the prior box, also when the box cuts the posterior through its mode (half its mass outside).
``gaussian_moments``
    the sample mean and covariance agree with the analytic ones within Monte-Carlo error: |mean − μ_i| ≤ z σ_i/√ESS_i,
    |var − σ_i²| ≤ z σ_i² √(2/ESS_i), |cov − Σ_12| ≤ z √((σ_1²σ_2² + Σ_12²)/ESS) (the standard errors of Gaussian
    sample moments from ESS effective draws; ESS is ArviZ's bulk ESS over chains), with at least ``min_ess``
    effective draws.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
import xarray as xr

from spflow.core.errors import SpflowError
from spflow.core.stage import Stage, StageContext

from .checklist import Broken, Check, Checklist, ConformanceReport
from .datasets import differences
from .gaussian_target import GaussianTarget, gaussian_target, linear_kind_registered

__all__ = ["check_sampler", "SAMPLER_CHECKS"]

_PORTS = ("surrogate", "observations", "space")
_PARAMS = ("experiments", "variables", "noise", "sigma", "surrogate_variance", "seed")

SAMPLER_CHECKS = {c.name: c for c in (
    Check("declaration", "a Stage with ports surrogate, observations and space and the shared sampler parameters",
          "subclass spflow.plugins.calibration.mcmc_stage.SamplerStage and implement _sample_runs"),
    Check("runs", "on a 2-D Gaussian target the sampler returns a POSTERIOR Dataset with finite log posteriors and "
          "acceptance rates in [0, 1]", "build the result with posterior.posterior_dataset (SamplerStage.run does)"),
    Check("seed_determinism", "the same seed gives identical draws, another seed other draws",
          "draw every random number from generators seeded by the 'seed' parameter (SeedSequence.spawn per chain)"),
    Check("prior_support", "every draw lies inside the prior box, also when the box cuts the posterior",
          "reject proposals outside the box (the log posterior is -inf there) instead of clipping them"),
    Check("gaussian_moments", "on the Gaussian target the sample mean and covariance agree with the analytic "
          "posterior within Monte-Carlo error from the draws' ESS",
          "check the acceptance rule (detailed balance: symmetric proposal or its Hastings correction) and that "
          "burn-in draws are discarded; if the ESS is too small raise the budget passed to check_sampler"),
)}


def _theta(posterior: xr.Dataset) -> np.ndarray:
    return posterior["theta"].transpose("chain", "draw", "param").values


class _SamplerRun:
    def __init__(self, cls: type[Stage], budget: Mapping[str, Any], seed: int, z: float, min_ess: float):
        self.cls, self.budget, self.seed, self.z, self.min_ess = cls, dict(budget), seed, z, min_ess
        self.target = gaussian_target()
        self.posterior: xr.Dataset | None = None

    def sample(self, target: GaussianTarget, seed: int) -> xr.Dataset:
        stage = self.cls(**{**self.budget, **target.params, "seed": seed})
        inputs = {p: ds.copy(deep=True) for p, ds in target.inputs.items()}
        with linear_kind_registered():
            return stage.run(StageContext(node=f"check_sampler[{self.cls.name}]", verbose=False), **inputs)

    def runs(self) -> None:
        from spflow.plugins.calibration.posterior import POSTERIOR

        out = self.sample(self.target, self.seed)
        if not isinstance(out, xr.Dataset):
            raise Broken(f"run() returned a {type(out).__name__}")
        try:
            POSTERIOR.validate(out, stage=self.cls.name, port="output")
        except SpflowError as exc:
            raise Broken(str(exc)) from None
        acceptance = out["acceptance"].values
        if not (np.isfinite(out["log_posterior"].values).all() and ((acceptance >= 0) & (acceptance <= 1)).all()):
            raise Broken("non-finite log posterior or acceptance outside [0, 1]")
        self.posterior = out

    def seed_determinism(self) -> None:
        found = differences(self.posterior, self.sample(self.target, self.seed))
        if found:
            raise Broken(f"a second run with seed {self.seed} differs: " + "; ".join(found))
        if np.array_equal(_theta(self.sample(self.target, self.seed + 1)), _theta(self.posterior)):
            raise Broken(f"seed {self.seed + 1} gives the same draws as seed {self.seed}: the seed is not used")

    def prior_support(self) -> None:
        for what, target, out in (("the wide box", self.target, self.posterior),
                                  ("a box cutting the posterior at its mode", (cut := gaussian_target(cut=True)),
                                   self.sample(cut, self.seed))):
            theta = _theta(out).reshape(-1, 2)
            lower, upper = target.space["lower"].values, target.space["upper"].values
            outside = int(((theta < lower) | (theta > upper)).any(axis=1).sum())
            if outside:
                raise Broken(f"{outside} of {len(theta)} draws lie outside {what} [{lower}, {upper}]")

    def gaussian_moments(self) -> None:
        import arviz as az

        theta = _theta(self.posterior)
        ess = np.array([float(az.ess(theta[..., i])) for i in range(theta.shape[-1])])
        if ess.min() < self.min_ess:
            raise Broken(f"only {ess.min():.0f} effective draws (need {self.min_ess:g}) from {theta.shape[0]} chains x "
                         f"{theta.shape[1]} draws")
        flat = theta.reshape(-1, theta.shape[-1])
        mean, cov = flat.mean(axis=0), np.cov(flat, rowvar=False)
        mu, sigma = self.target.mean, self.target.cov
        sd, z, problems = np.sqrt(np.diag(sigma)), self.z, []
        for i in range(2):
            if abs(mean[i] - mu[i]) > z * sd[i] / np.sqrt(ess[i]):
                problems.append(f"mean of parameter {i + 1} {mean[i]:.5g}, analytic {mu[i]:.5g} (allowed "
                                f"±{z * sd[i] / np.sqrt(ess[i]):.3g} at ESS {ess[i]:.0f})")
            if abs(cov[i, i] - sigma[i, i]) > z * sigma[i, i] * np.sqrt(2.0 / ess[i]):
                problems.append(f"variance of parameter {i + 1} {cov[i, i]:.4g}, analytic {sigma[i, i]:.4g} "
                                f"(allowed ±{z * sigma[i, i] * np.sqrt(2.0 / ess[i]):.3g})")
        se = np.sqrt((sigma[0, 0] * sigma[1, 1] + sigma[0, 1] ** 2) / ess.min())
        if abs(cov[0, 1] - sigma[0, 1]) > z * se:
            problems.append(f"covariance {cov[0, 1]:.4g}, analytic {sigma[0, 1]:.4g} (allowed ±{z * se:.3g})")
        if problems:
            raise Broken("; ".join(problems))


def _check_declaration(cls: Any) -> None:
    if not (isinstance(cls, type) and issubclass(cls, Stage)):
        raise Broken(f"{cls!r} is not a Stage subclass")
    missing = [p for p in _PORTS if p not in cls.inputs] + [p for p in _PARAMS if p not in cls.params]
    if missing:
        raise Broken(f"missing ports/parameters {missing}")


def check_sampler(sampler: type[Stage] | str, params: Mapping[str, Any] | None = None, *, seed: int = 0,
                  z: float = 4.0, min_ess: float = 200.0) -> ConformanceReport:
    """Run the sampler conformance checks (module docstring) on ``sampler`` (a stage class or a registered stage
    name) with budget ``params`` (``samples``, ``burn``, ``thin``, ``chains`` and the sampler's own; the target's
    ``experiments``, ``variables``, ``noise``, ``sigma``, ``surrogate_variance`` and ``seed`` are set by the check).
    The sampler runs four times on a 2-parameter linear model, so a budget of some 10^4 evaluations per chain keeps
    it to seconds. ``z`` is the tolerance in Monte-Carlo standard errors, ``min_ess`` the fewest effective draws
    accepted. Returns the report of passed checks or raises one :class:`~.checklist.ConformanceError`.
    """
    from spflow.core.plugins import get_registry

    cls = get_registry().stage(sampler) if isinstance(sampler, str) else sampler
    checks = Checklist(f"check_sampler({getattr(cls, 'name', cls)!r})")
    c = SAMPLER_CHECKS
    if not checks.run(c["declaration"], _check_declaration, cls):
        return checks.finish()
    run = _SamplerRun(cls, params or {}, seed, z, min_ess)
    checks.run(c["runs"], run.runs)
    for name in ("seed_determinism", "prior_support", "gaussian_moments"):
        checks.run(c[name], getattr(run, name), needs=("runs",))
    return checks.finish()
