"""Reduced clean synthetic twin of the chapter-4 calibration (the full 9-parameter one is scripts/twin_bayesian.py,
about 2-4 minutes on 2 cores; its numbers are in docs/calibration.md).

Same chain as the pipeline — twin corefloods -> observations -> LHS -> simulator -> PCE -> MH sampler -> simulator on
posterior draws of the held-out BCF2 — but with the three best-identified Table 4.1 parameters free (the others
fixed at the truth), 30 grid cells and a smaller MCMC budget. Checked: the truth inside every 95 % credible
interval, converged chains (R-hat, Geweke |z| < 2) and the 90 % predictive band covering most held-out points.

The twin is simulated on the calibration's own 0.1 PV output grid: at 30 cells the simulator's outputs depend on the
output step (its time steps land on the output points) by about 0.5 % in dp and 0.005 in oil cut, as much as the
measurement noise — a numerical model error that would make the twin unclean (at the script's 100 cells it is 0.14 %
and 0.001).
"""

import runpy
from pathlib import Path

import numpy as np

from spflow.core.stage import StageContext
from spflow.plugins.calibration.diagnostics import geweke_familywise, summary
from spflow.plugins.calibration.mh_sampler import MHSampler
from spflow.plugins.calibration.posterior_predictive import PosteriorPredictive
from spflow.plugins.design.latin_hypercube import LatinHypercubeDesign
from spflow.plugins.design.parameter_space import ParameterSpace
from spflow.plugins.design.thesis_tables import TABLE_4_1
from spflow.plugins.forward.stage import Forward
from spflow.plugins.observations import Observations
from spflow.plugins.surrogates.pce_stage import PCEStage
from spflow.synthetic import make_coreflood

ROOT = Path(__file__).resolve().parents[2]
TWIN = runpy.run_path(str(ROOT / "scripts" / "twin_bayesian.py"))
FREE = ["HBNC70", "AD31", "E2WC"]
CELLS = 30


def test_reduced_clean_twin(tmp_path):
    # the thesis profile's columns (Table 4.1: the oleic exponents E2C / E2WC), not the study's n_high / n_low
    truth = {k: v for k, v in TWIN["TRUTH"].items() if k not in ("n_high", "n_low")}
    fixed = {k: v for k, v in truth.items() if k not in FREE}
    ctx = StageContext("twin", n_jobs=1, verbose=False)
    files = []
    for k, experiment in enumerate(("BCF1", "BCF2")):
        path = tmp_path / f"{experiment}.nc"
        make_coreflood(experiment, truth, noise=TWIN["CLEAN_NOISE"], seed=30 + k, cells=CELLS,
                       pv_step=0.1).to_netcdf(path)
        files.append(str(path))
    observations = Observations(experiments=files).run(ctx)
    space = ParameterSpace(names=FREE, ranges={n: TABLE_4_1[n] for n in FREE}).run(ctx)
    design = LatinHypercubeDesign(samples=50, seed=3).run(ctx, space=space)
    responses = Forward(experiments=["BCF1"], fixed=fixed, cells=CELLS).run(ctx, design=design)
    surrogate = PCEStage(variables=["dp", "oil_cut"], degree_max=4).run(ctx, space=space, design=design,
                                                                        responses=responses)
    posterior = MHSampler(samples=24_000, burn=6_000, thin=5, chains=3, seed=5).run(
        ctx, surrogate=surrogate, observations=observations, space=space)
    table = summary(posterior)
    # Geweke: the family-wise level of the len(FREE) z-scores (Bonferroni, alpha = 0.01: a converged sampler
    # fails this check in 1 % of runs; per-parameter |z| < 2 would fail a converged one in 1 - 0.954^k of runs)
    z_limit = geweke_familywise(table["geweke_z"].values, alpha=0.01)["bonferroni_z"]
    for name in FREE:
        row = table.sel(param=name)
        assert float(row.q025) <= truth[name] <= float(row.q975), (name, float(row.q025), float(row.q975))
        assert float(row.rhat) < 1.01 and abs(float(row.geweke_z)) < z_limit, (name, float(row.rhat),
                                                                                 float(row.geweke_z), z_limit)
        # the data pin these parameters down: the posterior is much narrower than the prior box
        assert float(row.sd) < 0.2 * (TABLE_4_1[name][1] - TABLE_4_1[name][0]) / np.sqrt(12)
    bands = PosteriorPredictive(experiments=["BCF2"], draws=80, fixed=fixed, cells=CELLS, seed=6).run(
        ctx, posterior=posterior, space=space, observations=observations)
    points = sum(int(bands[f"points_{v}"].sel(experiment="BCF2")) for v in ("dp", "oil_cut"))
    inside = sum(float(bands[f"coverage_{v}"].sel(experiment="BCF2")) * int(bands[f"points_{v}"].sel(
        experiment="BCF2")) for v in ("dp", "oil_cut"))
    assert points > 60
    assert 0.8 <= inside / points <= 0.99
