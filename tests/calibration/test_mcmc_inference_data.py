"""The MCMC posterior as ArviZ InferenceData: written from a real (tiny) sampler run on the linear toy of
``test_mcmc_toys`` (f(θ) = Aθ + b, surrogate variance c), read back with ``az.from_netcdf``, and checked against the
toy's likelihood computed here with scipy, against the sampler's own per-draw log likelihood, and by ArviZ's
``loo``, ``summary`` and ``plot_trace``; every variable's units parsed by cf-units (``cf_check``)."""

import numpy as np
import pytest
from cf_check import dataset_problems
from scipy.stats import norm
from test_mcmc_toys import LinearToy, observations_for, outputs_for, space_for
from test_mcmc_toys import toy_kind_registered  # noqa: F401  (autouse fixture: registers the toy surrogate kind)

from spflow.core.errors import ParameterError
from spflow.core.figure import subplots
from spflow.core.stage import StageContext
from spflow.plugins.calibration.diagnostics import arviz
from spflow.plugins.calibration.emcee_sampler import EmceeSampler
from spflow.plugins.calibration.inference_data import to_inference_data, write_inference_data

NAMES = ["p", "q"]
BLOCKS = {("dp", "BCF1"): 7, ("oil_cut", "BCF1"): 5}
SIGMA, C = [0.5, 0.2], 0.05
TINY = {"samples": 1_600, "burn": 400, "thin": 2, "chains": 2, "walkers": 8, "seed": 3}
GROUPS = ["posterior", "sample_stats", "log_likelihood", "observed_data", "posterior_predictive", "prior",
          "constant_data"]


def _toy_run(noise, names=NAMES, **extra):
    rng = np.random.default_rng(8)
    index = outputs_for(BLOCKS)
    a, b = rng.normal(size=(len(index), 2)), rng.normal(size=len(index))
    scale = np.concatenate([np.full(n, s) for n, s in zip(BLOCKS.values(), SIGMA)])
    y = a @ np.array([0.4, -0.3]) + b + rng.normal(size=len(index)) * scale
    toy = LinearToy(names, [-4, -4], [4, 4], index, a, b, np.full(len(index), C))
    obs = observations_for(index, y)
    posterior = EmceeSampler(noise=noise, **extra, **TINY).run(
        StageContext("posterior", verbose=False), surrogate=toy.to_dataset(), observations=obs,
        space=space_for(names, [-3, -3], [3, 3]))
    return posterior, toy, obs, a, b, y


@pytest.mark.parametrize("noise, extra", [("known", {"sigma": SIGMA}), ("jeffreys_sampled", {})])
def test_file_reads_back_and_pointwise_log_likelihood_is_the_toys(tmp_path, noise, extra):
    az = arviz()
    posterior, toy, obs, a, b, y = _toy_run(noise, **extra)
    path = write_inference_data(tmp_path / "posterior.nc", posterior, toy.to_dataset(), obs, prior_draws=300)
    idata = az.from_netcdf(path)
    assert sorted(idata.groups()) == sorted(GROUPS)
    theta = np.stack([idata.posterior[n].values for n in NAMES], axis=-1)  # (chain, draw, 2)
    np.testing.assert_array_equal(theta, posterior["theta"].values)
    sigma = np.stack([idata.posterior[f"sigma_{v}_{e}"].values for v, e in BLOCKS], axis=-1)
    # the toy's Gaussian log density of each observation, block by block
    scale = np.sqrt(np.repeat(sigma, list(BLOCKS.values()), axis=-1) ** 2 + C)
    expected = norm.logpdf(y, loc=theta @ a.T + b, scale=scale)
    pointwise = idata.log_likelihood["y"].values
    np.testing.assert_allclose(pointwise, expected, rtol=1e-10, atol=1e-10)
    # with known or sampled noise the terms add up to what the sampler recorded for each draw
    np.testing.assert_allclose(pointwise.sum(axis=-1), posterior["log_likelihood"].values, rtol=1e-10)
    np.testing.assert_allclose(idata.sample_stats["log_likelihood"].values, posterior["log_likelihood"].values)
    np.testing.assert_array_equal(idata.observed_data["dp_BCF1"].values, y[:7])
    np.testing.assert_array_equal(idata.observed_data["oil_cut_BCF1"].values, y[7:])
    # replicated data: (y_rep - Aθ - b) / sqrt(σ² + c) is standard normal over all draws and observations
    rep = np.concatenate([idata.posterior_predictive[f"{v}_{e}"].values for v, e in BLOCKS], axis=-1)
    z = ((rep - theta @ a.T - b) / scale).ravel()
    assert abs(z.mean()) < 4 / np.sqrt(z.size) and abs(z.std() - 1) < 4 / np.sqrt(2 * z.size)
    prior = np.stack([idata.prior[n].values for n in NAMES], axis=-1)
    assert prior.shape == (1, 300, 2) and prior.min() >= -3 and prior.max() <= 3


def test_arviz_tools_run_on_the_file_and_every_variable_has_units_and_a_long_name(tmp_path):
    az = arviz()
    posterior, toy, obs, *_ = _toy_run("jeffreys_marginal")
    idata = az.from_netcdf(write_inference_data(tmp_path / "posterior.nc", posterior, toy.to_dataset(), obs))
    loo = az.loo(idata, pointwise=True)
    assert np.isfinite(loo["elpd_loo"]) and loo["loo_i"].size == sum(BLOCKS.values())
    # elpd_loo <= lppd (the within-sample fit): the penalty p_loo is positive
    lppd = float(np.sum(np.log(np.mean(np.exp(idata.log_likelihood["y"].values), axis=(0, 1)))))
    assert loo["elpd_loo"] < lppd and loo["p_loo"] == pytest.approx(lppd - loo["elpd_loo"], rel=1e-6)
    table = az.summary(idata)
    assert set(table.index) == {"p", "q", "sigma_dp_BCF1", "sigma_oil_cut_BCF1"}
    np.testing.assert_allclose(table.loc["p", "mean"], posterior["theta"].sel(param="p").values.mean(), atol=1e-3)
    fig, axes = subplots(4, 2, figsize=(8, 8))
    az.plot_trace(idata, axes=axes)
    fig.savefig(tmp_path / "trace.png")
    assert (tmp_path / "trace.png").stat().st_size > 0 and axes[0, 0].get_title() == "p"
    for group in GROUPS:
        ds = idata[group]
        assert ds.attrs["Conventions"] == "CF-1.10", group
        assert dataset_problems(ds, per_element=False) == [], group
    assert idata.posterior["sigma_dp_BCF1"].attrs["units"] == "Pa"
    assert idata.observed_data["oil_cut_BCF1"].attrs["units"] == "1"


def test_other_observations_than_the_posteriors_are_refused():
    posterior, toy, obs, *_ = _toy_run("jeffreys_marginal")
    fewer = obs.copy(deep=True)
    fewer["dp"][0, 0] = np.nan
    with pytest.raises(ParameterError, match="not the same observations"):
        to_inference_data(posterior, toy.to_dataset(), fewer)
    with pytest.raises(ParameterError, match="prior_draws"):
        to_inference_data(posterior, toy.to_dataset(), obs, prior_draws=0)
    with pytest.raises(ParameterError, match="thin"):
        to_inference_data(posterior, toy.to_dataset(), obs, thin=0)


def test_thinning_keeps_every_kth_draw_and_says_so(tmp_path):
    posterior, toy, obs, *_ = _toy_run("known", sigma=SIGMA)
    idata = to_inference_data(posterior, toy.to_dataset(), obs, thin=3)
    np.testing.assert_array_equal(idata.posterior["p"].values, posterior["theta"].sel(param="p").values[:, ::3])
    assert idata.log_likelihood["y"].shape[:2] == (posterior.sizes["chain"], -(-posterior.sizes["draw"] // 3))
    np.testing.assert_allclose(idata.log_likelihood["y"].values.sum(axis=-1),
                               posterior["log_likelihood"].values[:, ::3], rtol=1e-10)
    assert all(idata[g].attrs["thinned_by"] == 3 for g in idata.groups())


def test_a_plain_netcdf_file_is_not_read_as_a_posterior(tmp_path):
    from spflow.plugins.calibration.inference_data import read_posterior

    posterior, *_ = _toy_run("jeffreys_marginal")
    posterior.to_netcdf(tmp_path / "plain.nc")
    with pytest.raises(ParameterError, match="plain.nc.*not an MCMC posterior written as InferenceData"):
        read_posterior(tmp_path / "plain.nc")


def test_the_opm_export_reads_the_draws_back_from_the_file(tmp_path):
    from spflow.export.opm_model import posterior_parameters

    posterior, toy, obs, *_ = _toy_run("jeffreys_marginal", names=["AP1", "AP3"])
    path = write_inference_data(tmp_path / "posterior.nc", posterior, toy.to_dataset(), obs)
    theta = posterior["theta"].values
    mean, where = posterior_parameters(path, "mean")
    assert mean == pytest.approx({"AP1": theta[..., 0].mean(), "AP3": theta[..., 1].mean()}, rel=1e-12)
    k = theta.shape[1] + 3  # chain 1, draw 3
    one, where = posterior_parameters(path, str(k))
    assert one == {"AP1": theta[1, 3, 0], "AP3": theta[1, 3, 1]} and "chain 1, draw 3" in where


def test_the_posterior_summary_keeps_the_draws_units():
    from spflow.plugins.calibration.diagnostics import summary

    posterior, *_ = _toy_run("jeffreys_sampled")
    for variable, dim, holder in (("theta", "param", "unit"), ("sigma", "block", "block_units")):
        table = summary(posterior, variable, dim)
        assert dataset_problems(table) == []
        assert table["mean"].attrs["units_variable"] == holder and table["q975"].attrs["units_variable"] == holder
        assert table[holder].values.tolist() == posterior[holder].values.tolist()
        assert table["ess_bulk"].attrs["units"] == "1"
