"""The posterior_predictive stage against brute-force simulator runs and exact noise/coverage arithmetic."""

import numpy as np
import pytest
import xarray as xr

from spflow.core.errors import ParameterError
from spflow.core.stage import StageContext
from spflow.plugins.calibration.posterior import posterior_dataset
from spflow.plugins.calibration.posterior_predictive import PosteriorPredictive
from spflow.plugins.design.parameter_space import ParameterSpace
from spflow.plugins.forward.simulate import simulate

NAMES = ["CRK", "E2WC"]
CTX = StageContext("predictive", verbose=False)
CELLS = 20


def _space():
    return ParameterSpace(names=NAMES, ranges={"CRK": [0.06, 0.08], "E2WC": [1.5, 2.5]}).run(CTX)


def _posterior(theta, sigma):
    theta = np.asarray(theta, float)[None]  # one chain
    sigma = np.broadcast_to(np.asarray(sigma, float), theta.shape[:2] + (2,))
    n = theta.shape[1]
    return posterior_dataset(theta, sigma, np.zeros((1, n)), np.zeros((1, n)), np.array([0.3]), space=_space(),
                             pairs=[("dp", "BCF1"), ("oil_cut", "BCF1")], points=[40, 40], units=["Pa", "1"],
                             attrs={"sampler": "test", "noise": "known"})


def test_model_bands_are_quantiles_of_simulator_runs_at_the_draws():
    theta = [[0.062, 1.6], [0.07, 2.0], [0.075, 2.4], [0.066, 1.9], [0.079, 2.2]]
    stage = PosteriorPredictive(experiments=["BCF1", "BCF3"], draws=5, levels=[0.1, 0.5, 0.9], noise=False,
                                cells=CELLS)
    bands = stage.run(CTX, posterior=_posterior(theta, [100.0, 0.01]), space=_space())
    for experiment in ("BCF1", "BCF3"):
        runs = np.array([simulate(experiment, dict(zip(NAMES, t)), cells=CELLS, pv_step=0.1)["dp"].values
                         for t in theta])
        got = bands["dp"].sel(experiment=experiment).dropna("pv", how="all")
        np.testing.assert_allclose(got.values, np.quantile(runs, [0.1, 0.5, 0.9], axis=0), rtol=1e-12)
    np.testing.assert_allclose(bands["theta"].sel(quantile=0.5).values, np.median(theta, axis=0))
    assert "dp_predictive" not in bands and bands.attrs["draws"] == 5


def test_predictive_noise_and_coverage():
    """All draws at one θ: the model band collapses onto the simulation, the predictive band is the simulation ± the
    normal quantile times σ; BCF2 is held out, so it takes the noise of the BCF1 blocks."""
    draws, sigma_dp = 150, 400.0
    theta = np.tile([0.07, 2.0], (draws, 1))
    run = simulate("BCF2", dict(zip(NAMES, theta[0])), cells=CELLS, pv_step=0.1)
    observed = xr.Dataset({"dp": (("experiment", "pv"), run["dp"].values[None] + 0.0, {"units": "Pa"}),
                           "oil_cut": (("experiment", "pv"), run["oil_cut"].values[None] + 10.0, {"units": "1"})},
                          coords={"experiment": ["BCF2"], "pv": run["pv"].values})
    stage = PosteriorPredictive(experiments=["BCF2"], draws=draws, levels=[0.1, 0.5, 0.9], cells=CELLS, seed=4)
    bands = stage.run(CTX, posterior=_posterior(theta, [sigma_dp, 0.02]), space=_space(), observations=observed)
    sel = bands.sel(experiment="BCF2").dropna("pv", how="all")
    np.testing.assert_allclose(sel["dp"].sel(quantile=0.1), run["dp"].values, rtol=1e-12)
    low = (sel["dp_predictive"].sel(quantile=0.1) - run["dp"].values) / sigma_dp
    high = (sel["dp_predictive"].sel(quantile=0.9) - run["dp"].values) / sigma_dp
    # sample 10 %/90 % quantiles of 150 normal draws: sd about 0.14 sigma around -/+1.2816
    assert float(np.median(low)) == pytest.approx(-1.2816, abs=0.15)
    assert float(np.median(high)) == pytest.approx(1.2816, abs=0.15)
    assert float(bands["coverage_dp"].sel(experiment="BCF2")) == 1.0
    assert float(bands["model_coverage_dp"].sel(experiment="BCF2")) == 1.0  # degenerate band, observation on it
    assert float(bands["coverage_oil_cut"].sel(experiment="BCF2")) == 0.0
    assert int(bands["points_dp"].sel(experiment="BCF2")) == int(np.isfinite(run["dp"].values).sum())


def test_bad_input_is_named():
    with pytest.raises(ParameterError, match="levels"):
        PosteriorPredictive(levels=[0.5])
    post = _posterior([[0.07, 2.0], [0.071, 2.1]], [1.0, 0.1])
    with pytest.raises(ParameterError, match="exceeds the 2 posterior draws"):
        PosteriorPredictive(draws=3, cells=CELLS).run(CTX, posterior=post, space=_space())
    other = ParameterSpace(names=["CRK"], ranges={"CRK": [0.06, 0.08]}).run(CTX)
    with pytest.raises(ParameterError, match="'E2WC' is not in the space"):
        PosteriorPredictive(draws=2, cells=CELLS).run(CTX, posterior=post, space=other)
