"""An MCMC posterior as ArviZ ``InferenceData`` (one netCDF file, one group per kind of draw), for ``az.loo``,
``az.summary``, ``az.plot_trace`` and any other ArviZ tool.

:func:`to_inference_data` rebuilds the posterior model of thesis §4.6 (Eqs. 4.2-4.5: the prior of the parameters, uniform on
the box or the marginals the posterior records (:mod:`.parameter_prior`), Gaussian likelihood per QoI block, surrogate for the forward model) from the sampler's Dataset, the surrogate and the
observations it was trained on, and returns the groups

* ``posterior``: one variable per calibrated parameter θ_j (chain, draw) in its design column's unit (log10 of the
  value for a log-scale column), and one per block noise level ``sigma_<variable>_<experiment>`` in the block's unit;
* ``sample_stats``: ``lp`` (log posterior) and ``log_likelihood`` per draw as the sampler recorded them, and each
  chain's acceptance fraction (``chain_acceptance``);
* ``log_likelihood``: ``y`` (chain, draw, observation), log N(d_k; f_k(θ), σ_i² + v_k(θ)) of every observation k
  (:meth:`~.likelihood.PosteriorModel.pointwise_log_likelihood`). With known or sampled σ_i its sum over k is the
  sampler's per-draw log likelihood; with σ_i integrated out (``noise = "jeffreys_marginal"``) the sampler records
  the marginal, which has no per-observation form, and ``y`` is conditional on the draw's σ_i (drawn from
  p(σ_i | θ, d)), so the sums differ from the recorded values;
* ``observed_data``: the observations of each block ``<variable>_<experiment>`` (dim ``<variable>_<experiment>_pv``)
  in their unit;
* ``posterior_predictive``: new observations of each block drawn at every posterior draw from Eq. 4.3 with the
  surrogate for the forward model (the simulator's predictive bands are the ``posterior_predictive`` stage's);
* ``prior``: draws of θ from its prior (uniform in the box, Eq. 4.2, or the recorded marginals); the Jeffreys prior of
  σ_i is improper and not drawn;
* ``constant_data``: each parameter's prior range (dim ``bound``), its prior law (``distribution`` /
  ``distribution_parameters`` along ``param``, when the posterior records them) and the parameter map (which forward-model
  parameters each column sets, on which scale), so that :func:`read_posterior` gives the draws back as a sampler
  stage's Dataset (the OPM export reads the file through it).

Every numeric variable carries a UDUNITS ``units`` (with ``equivalents`` or ``currency`` where UDUNITS cannot say
what is counted, :func:`~spflow.core.cf_metadata.unit_notes`) and every variable a ``long_name``, and each group
claims ``Conventions = "CF-1.10"`` (:mod:`spflow.core.cf_metadata`). :func:`write_inference_data` writes the file; the
``bayesian_calibration`` report writes it as ``posterior.nc``. ArviZ is imported only here, when called
(:func:`~.diagnostics.arviz`).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import xarray as xr

from spflow.core.cf_metadata import CONVENTIONS, claims_cf, note_units, udunits
from spflow.core.errors import ParameterError
from spflow.plugins.design.parameter_map import NAMES_VAR, SCALE_VAR
from spflow.plugins.surrogates.contract import load_surrogate

from .aligned_data import align
from .diagnostics import arviz
from .likelihood import PosteriorModel
from .parameter_prior import ParameterPrior
from .posterior import POSTERIOR

__all__ = ["to_inference_data", "from_run", "write_inference_data", "read_posterior", "posterior_model"]

#: Rows of draws evaluated per surrogate call (bounds the memory of one call).
_CHUNK = 4096


def posterior_model(posterior: xr.Dataset, surrogate: xr.Dataset, observations: xr.Dataset) -> PosteriorModel:
    """The posterior model a sampler stage sampled, rebuilt from its output ``posterior``, the fitted ``surrogate``
    and the ``observations``; raises :class:`ParameterError` if they are not the ones the posterior was drawn with
    (other parameters, or other observation counts per block)."""
    POSTERIOR.validate(posterior, stage="to_inference_data", port="posterior", values=False)
    sur = load_surrogate(surrogate)
    names = [str(n) for n in posterior["param"].values]
    if names != list(sur.names):
        raise ParameterError(f"to_inference_data: the posterior's parameters {names} are not the surrogate's "
                             f"{list(sur.names)} (in that order)")
    pairs = [(str(v), str(e)) for v, e in zip(posterior["block_variable"].values, posterior["block_experiment"].values)]
    noise = str(posterior.attrs["noise"])
    sigma = tuple(float(s) for s in posterior["sigma"].values[0, 0]) if noise == "known" else ()
    model = PosteriorModel(sur, align(sur.outputs, observations, pairs), pairs,
                           posterior["lower"].values.astype(float), posterior["upper"].values.astype(float),
                           noise=noise, sigma=sigma,
                           surrogate_variance=bool(int(posterior.attrs.get("surrogate_variance", 1))),
                           prior=ParameterPrior.of_posterior(posterior, "to_inference_data: the posterior"))
    if "block_points" in posterior and list(model.points()) != [int(n) for n in posterior["block_points"].values]:
        raise ParameterError(f"to_inference_data: the observations give {model.points()} points per block "
                             f"{[f'{v}/{e}' for v, e in pairs]}, the posterior was drawn with "
                             f"{[int(n) for n in posterior['block_points'].values]}: not the same observations")
    return model


def _name(*parts: str) -> str:
    name = "_".join(parts)
    if "/" in name or not name:
        raise ParameterError(f"to_inference_data: {name!r} cannot name a netCDF variable (no '/' allowed)")
    return name


def _stamp(ds: xr.Dataset, title: str) -> xr.Dataset:
    """``ds`` with its title, the chain and draw coordinates' metadata, the notes of its units
    (:func:`~spflow.core.cf_metadata.note_units`) and ``Conventions`` when it qualifies."""
    ds.attrs["title"] = title
    for dim in ("chain", "draw"):
        if dim in ds.coords:
            ds[dim].attrs.update(units="1", long_name=f"MCMC {dim} number")
    ds = note_units(ds)
    if claims_cf(ds):
        ds.attrs["Conventions"] = CONVENTIONS
    return ds


def to_inference_data(posterior: xr.Dataset, surrogate: xr.Dataset, observations: xr.Dataset, *,
                      prior_draws: int = 1000, seed: int = 0, thin: int = 1):
    """The ``az.InferenceData`` of a sampler stage's ``posterior`` (module docstring); ``surrogate`` and
    ``observations`` are the Datasets the sampler was given; ``prior_draws`` prior draws of θ and the
    predictive noise come from ``seed``; ``thin``: keep every ``thin``-th draw of each chain (recorded as the
    groups' attribute ``thinned_by``)."""
    for name, value in (("prior_draws", prior_draws), ("thin", thin)):
        if not isinstance(value, int) or isinstance(value, bool) or value < 1:
            raise ParameterError(f"to_inference_data: {name} must be a positive integer, got {value!r}")
    az = arviz()
    model = posterior_model(posterior, surrogate, observations)
    posterior = posterior.isel(draw=slice(None, None, thin))
    chains, draws = posterior.sizes["chain"], posterior.sizes["draw"]
    names = [str(n) for n in posterior["param"].values]
    units = [udunits(u) for u in posterior["unit"].values]
    scales = [str(s) for s in posterior["scale"].values] if "scale" in posterior else ["linear"] * len(names)
    blocks = [_name(v, e) for v, e in model.pairs]
    block_units = [udunits(model.surrogate.outputs.units.get(v, "1")) for v, _ in model.pairs]
    if len(set(names + [f"sigma_{b}" for b in blocks])) != len(names) + len(blocks):
        raise ParameterError(f"to_inference_data: parameter names {names} clash with the noise levels "
                             f"{[f'sigma_{b}' for b in blocks]}")
    coords = {"chain": np.arange(chains), "draw": np.arange(draws)}
    theta = posterior["theta"].transpose("chain", "draw", "param").values
    sigma = posterior["sigma"].transpose("chain", "draw", "block").values
    what = {"linear": "", "log": "log10 of "}

    post = xr.Dataset(
        {name: (("chain", "draw"), theta[..., k], {"units": unit, "long_name": f"{what[scale]}{name}"})
         for k, (name, unit, scale) in enumerate(zip(names, units, scales))}
        | {f"sigma_{b}": (("chain", "draw"), sigma[..., i], {"units": unit, "long_name": f"noise standard deviation "
                                                             f"of {v} in {e} (Eq. 4.3)"})
           for i, (b, unit, (v, e)) in enumerate(zip(blocks, block_units, model.pairs))},
        coords=coords)

    flat_theta, flat_sigma = theta.reshape(-1, len(names)), sigma.reshape(-1, len(blocks))
    rng = np.random.default_rng(seed)
    pointwise, replicated = [], []
    for rows in np.array_split(np.arange(flat_theta.shape[0]), -(-flat_theta.shape[0] // _CHUNK)):
        pointwise.append(model.pointwise_log_likelihood(flat_theta[rows], flat_sigma[rows]))
        replicated.append(model.predictive_draws(flat_theta[rows], flat_sigma[rows], rng))
    pointwise = np.concatenate(pointwise).reshape(chains, draws, -1)
    replicated = np.concatenate(replicated).reshape(chains, draws, -1)
    points = np.cumsum([0, *model.points()])
    pv = [np.asarray(model.aligned.blocks[p][2], dtype=float) for p in model.pairs]
    obs_coords = {f"{b}_pv": (f"{b}_pv", pv[i], {"units": "1", "long_name": f"injected pore volumes of the {b} "
                                                                              "observations"})
                  for i, b in enumerate(blocks)}

    observation = np.concatenate([[f"{v}/{e}"] * n for (v, e), n in zip(model.pairs, model.points())])
    log_lik = xr.Dataset(
        {"y": (("chain", "draw", "observation"), pointwise,
               {"units": "1", "long_name": "log likelihood of each observation (Eq. 4.3, natural log)"})},
        coords=coords | {"observation": ("observation", np.arange(observation.size),
                                         {"units": "1", "long_name": "observation number, blocks in order"}),
                         "observation_block": ("observation", observation,
                                               {"long_name": "QoI block (variable/experiment) of the observation"}),
                         "observation_pv": ("observation", np.concatenate(pv),
                                            {"units": "1", "long_name": "injected pore volumes of the observation"})})
    observed = xr.Dataset(
        {b: (f"{b}_pv", model.observed[i], {"units": block_units[i], "long_name": f"observed {v} of {e}"})
         for i, (b, (v, e)) in enumerate(zip(blocks, model.pairs))}, coords=obs_coords)
    predictive = xr.Dataset(
        {b: (("chain", "draw", f"{b}_pv"), replicated[..., points[i]:points[i + 1]],
             {"units": block_units[i], "long_name": f"replicated {v} of {e} (Eq. 4.3, surrogate forward model)"})
         for i, (b, (v, e)) in enumerate(zip(blocks, model.pairs))}, coords=coords | obs_coords)
    stats = xr.Dataset(
        {"lp": (("chain", "draw"), posterior["log_posterior"].values,
                {"units": "1", "long_name": "log posterior density (Eqs. 4.1-4.5, natural log)"}),
         "log_likelihood": (("chain", "draw"), posterior["log_likelihood"].values,
                            {"units": "1", "long_name": f"log likelihood recorded by the sampler (noise "
                                                        f"{model.noise})"}),
         "chain_acceptance": ("chain", posterior["acceptance"].values,
                              {"units": "1", "long_name": "acceptance fraction of the chain"})},
        coords=coords)
    prior_theta = model.prior.sample((1, prior_draws), rng)
    prior = xr.Dataset(
        {name: (("chain", "draw"), prior_theta[..., k], {"units": unit, "long_name": f"{what[scale]}{name}, prior "
                                                                                     f"{law!r} (Eq. 4.2)"})
         for k, (name, unit, scale, law) in enumerate(zip(names, units, scales, model.prior.inputs))},
        coords={"chain": [0], "draw": np.arange(prior_draws)})
    constant = xr.Dataset(
        {name: ("bound", posterior[["lower", "upper"]].sel(param=name).to_array().values.astype(float),
                {"units": unit, "long_name": f"prior range of {what[scale]}{name} (Eq. 4.2)"})
         for name, unit, scale in zip(names, units, scales)}
        | {var: ("param", posterior[var].values.astype(str), dict(posterior[var].attrs))
           for var in (NAMES_VAR, SCALE_VAR, "distribution", "distribution_parameters") if var in posterior},
        coords={"bound": ("bound", ["lower", "upper"], {"long_name": "end of the range"}),
                "param": ("param", names, {"long_name": "calibrated parameter (design column)"})})
    sampler = {k: posterior.attrs[k] for k in ("sampler", "noise", "surrogate") if k in posterior.attrs}
    sampler["thinned_by"] = thin
    groups = {"posterior": post, "sample_stats": stats, "log_likelihood": log_lik, "observed_data": observed,
              "posterior_predictive": predictive, "prior": prior, "constant_data": constant}
    groups = {group: _stamp(ds, f"spflow MCMC posterior: {group}") for group, ds in groups.items()}
    for ds in groups.values():
        ds.attrs.update(sampler)
    return az.InferenceData(**groups)


def from_run(result, posterior: str = "posterior", surrogate: str = "surrogate", observations: str = "observations",
             **kwargs):
    """:func:`to_inference_data` of a run's result (``spflow.run(...)``), its sampler node ``posterior`` and the
    nodes ``surrogate`` and ``observations`` that fed it (the names of ``bayesian_calibration``)."""
    return to_inference_data(result[posterior], result[surrogate], result[observations], **kwargs)


def read_posterior(path: str | Path) -> xr.Dataset:
    """The draws of θ in a file of :func:`write_inference_data` as a sampler stage's Dataset holds them: ``theta``
    (chain, draw, param) with the parameter map (:mod:`spflow.plugins.design.parameter_map`); read with xarray
    (no ArviZ). Raises :class:`ParameterError` naming the file if it has no ``posterior`` and ``constant_data``
    groups."""
    try:
        with xr.open_dataset(path, group="constant_data") as constant, xr.open_dataset(path, group="posterior") as post:
            names = [str(n) for n in constant["param"].values]
            theta = np.stack([post[n].transpose("chain", "draw").values for n in names], axis=-1)
            ds = xr.Dataset({"theta": (("chain", "draw", "param"), theta)},
                            coords={"chain": post["chain"].values, "draw": post["draw"].values, "param": names})
            return ds.assign({var: constant[var].load() for var in (NAMES_VAR, SCALE_VAR) if var in constant})
    except (OSError, KeyError, ValueError) as exc:
        raise ParameterError(f"{path}: not an MCMC posterior written as InferenceData (needs the groups 'posterior' "
                             f"and 'constant_data' with every parameter; {type(exc).__name__}: {exc})") from None


def write_inference_data(path: str | Path, posterior: xr.Dataset, surrogate: xr.Dataset, observations: xr.Dataset,
                         **kwargs) -> Path:
    """Write :func:`to_inference_data` of the arguments to the netCDF file ``path`` (its groups as netCDF groups)
    and return the path."""
    path = Path(path)
    to_inference_data(posterior, surrogate, observations, **kwargs).to_netcdf(str(path))
    return path
