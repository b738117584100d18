"""Chapter-4 Bayesian history matching: forward model -> design -> PCE proxy -> MCMC -> posterior predictive.

The thesis's §4.5-4.6 as one cached DAG on a study's corefloods (default: the bundled study, BCF1-3; or any
coreflood files with the study's names, e.g. synthetic twins). The study's ``calibration`` experiments train the proxy
and the posterior, its ``heldout`` ones are predicted (bundled: BCF1 + BCF2 train, BCF3 is held out;
``profile="thesis"``: BCF1 alone trains and Table 4.1 is the prior, as in the thesis):

1. ``space``: the study's calibrated parameters (uniform prior, Eq. 4.2, in each design column: a log-scale
   parameter's column is log10 of its value, so its prior is log-uniform); bundled: the Table 3.2 ranges.
   ``profile="thesis"``: thesis Table 4.1 (narrower than Table 3.2; n_high / n_low = the oleic exponents).
2. ``design`` (Latin hypercube) -> ``responses`` (simulator on the training corefloods, each with its own core, rate
   and schedule) -> ``surrogate``: the ``pce`` stage on pressure drop and oil cut of the training corefloods (§4.5).
   Swap the proxy with ``surrogate="pck"`` (or ``p.set_stage("surrogate", "pck", {...})``): every surrogate stage
   has the same inputs and output.
3. ``observations`` -> ``posterior``: ``emcee_sampler`` (default) or ``mh_sampler`` (``sampler="mh_sampler"``, the
   thesis's Metropolis-Hastings), Gaussian likelihood per QoI with its own Jeffreys noise level integrated out and the
   proxy's error variance added (Eqs. 4.1-4.5), thesis budget 10^5 / 20 000 / 5 per chain, 4 chains.
4. ``predictive``: the simulator on 200 posterior draws for every observed coreflood (training and held out):
   quantile bands with and without measurement noise and the coverage of the observations (Figs. 4.4-4.5).
5. ``prior_design`` -> ``prior_responses`` -> ``prior_bands``: the prior response spread, drawn under Fig. 4.5 (a
   Latin hypercube of the space's prior: uniform on the box, or its recorded marginals, as ``lhs_design`` draws).

    spflow run bayesian_calibration --jobs 2
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

import spflow
from spflow.core.report_table import Table
from spflow.pipelines.history_matching import space_params, study_inputs
from spflow.plugins.design.thesis_tables import TABLE_4_1

QOIS = ["dp", "oil_cut"]
LEVELS = [0.05, 0.5, 0.95]
#: Most draws (over all chains) the report's InferenceData file keeps (thinned evenly along each chain).
IDATA_DRAWS = 16_000


def pipeline(samples: int = 300, cells: int = 100, degree_max: int = 3, sampler: str = "emcee_sampler",
             surrogate: str = "pce", chains: int = 4, mcmc_samples: int = 100_000, burn: int = 20_000,
             thin: int = 5, draws: int = 200, prior_draws: int = 64, seed: int = 2024,
             study=None, profile: str = "study", observed: list[str] | None = None,
             quick: bool = False) -> spflow.Pipeline:
    """The chapter-4 DAG on ``study`` (a study file, a Study, or ``None``: the bundled study). ``profile``: one of
    ``PROFILES`` (see :func:`spflow.pipelines.history_matching.study_inputs`); ``observed``: coreflood files
    replacing the study's data (their ``experiment`` attrs must be the study's names); ``quick``: small budgets."""
    if quick:
        samples, cells, degree_max, mcmc_samples, burn, draws, prior_draws = 80, 40, 2, 20_000, 5_000, 40, 16
    inputs = study_inputs(study, profile)
    observed_all = inputs.forward(inputs.observed)
    model = {"cells": cells, **inputs.model()}
    p = spflow.Pipeline("bayesian_calibration_quick" if quick else "bayesian_calibration")
    p.add("space", "parameter_space", params=space_params(inputs, profile, TABLE_4_1))
    p.add("design", "lhs_design", inputs={"space": "space"}, params={"samples": samples, "seed": seed})
    p.add("responses", "forward", inputs={"design": "design"},
          params={"experiments": inputs.forward(inputs.training), **model})
    proxy = {"variables": QOIS, "experiments": inputs.training_names}
    p.add("surrogate", surrogate, inputs={"space": "space", "design": "design", "responses": "responses"},
          params=proxy | ({"degree_max": degree_max} if surrogate == "pce" else {}))
    p.add("observations", "observations",
          params={"experiments": list(observed) if observed else inputs.observations(inputs.observed)})
    p.add("posterior", sampler, inputs={"surrogate": "surrogate", "observations": "observations", "space": "space"},
          params={"experiments": inputs.training_names, "variables": QOIS, "chains": chains, "samples": mcmc_samples,
                  "burn": burn, "thin": thin, "seed": seed})
    p.add("predictive", "posterior_predictive",
          inputs={"posterior": "posterior", "space": "space", "observations": "observations"},
          params={"experiments": observed_all, "draws": draws, "levels": LEVELS, "seed": seed, **model})
    p.add("prior_design", "lhs_design", inputs={"space": "space"}, params={"samples": prior_draws, "seed": seed + 1})
    p.add("prior_responses", "forward", inputs={"design": "prior_design"},
          params={"experiments": observed_all, **model})
    p.add("prior_bands", "quantiles", inputs={"ensemble": "prior_responses"}, params={"levels": LEVELS})
    return p


def report(result: spflow.RunResult, outdir: Path, truth: dict[str, float] | None = None) -> list[str | Table]:
    """Appendix B-E figures, Figs. 4.4-4.5, the posterior as ArviZ InferenceData (``posterior.nc``,
    :mod:`spflow.plugins.calibration.inference_data`), the predictive Dataset, and a summary table."""
    from spflow.plugins.calibration import mcmc_figures as fig
    from spflow.plugins.calibration.diagnostics import summary
    from spflow.plugins.calibration.inference_data import write_inference_data

    posterior, bands = result["posterior"], result["predictive"]
    observations, prior = result["observations"], result["prior_bands"]
    # at most IDATA_DRAWS draws in the file: its pointwise log likelihood and replicated data hold one value per draw
    # and observation (the thesis budget's 64 000 draws of 150 observations made a 155 MB file)
    thin = -(-posterior.sizes["chain"] * posterior.sizes["draw"] // IDATA_DRAWS)
    write_inference_data(outdir / "posterior.nc", posterior, result["surrogate"], observations, thin=thin)
    bands.to_netcdf(outdir / "predictive.nc")
    training = list(dict.fromkeys(str(e) for e in posterior["block_experiment"].values))
    heldout = [str(e) for e in bands["experiment"].values if str(e) not in training]
    written = [
        fig.trace_figure(posterior, outdir / "fig_b1_traces.png"),
        fig.autocorrelation_figure(posterior, outdir / "fig_c1_autocorrelation.png"),
        fig.prior_posterior_figure(posterior, outdir / "fig_d1_prior_posterior.png", truth=truth),
        fig.geweke_figure(posterior, outdir / "fig_e1_geweke.png"),
        fig.predictive_figure(bands, observations, training, outdir / "fig_4_4_training.png", prior=prior,
                              title=f"Fig. 4.4: posterior prediction of the training corefloods {', '.join(training)}"),
    ]
    if heldout:
        written.append(fig.predictive_figure(
            bands, observations, heldout, outdir / "fig_4_5_heldout.png", prior=prior,
            title=f"Fig. 4.5: posterior prediction of the held-out corefloods {', '.join(heldout)}"))
    table = summary(posterior)
    noise = summary(posterior, "sigma", "block")
    lines = [f"wrote {len(written)} figures, posterior.nc (ArviZ InferenceData, az.from_netcdf; every {thin}-th draw "
             f"of each chain) and predictive.nc to {outdir}",
             f"sampler {posterior.attrs['sampler']} ({posterior.sizes['chain']} chains x {posterior.sizes['draw']} "
             f"draws), noise {posterior.attrs['noise']}, surrogate {posterior.attrs['surrogate']}, acceptance "
             f"{float(posterior['acceptance'].mean()):.2f}"]
    units = [str(u) for u in posterior["unit"].values] if "unit" in posterior else [""] * table.sizes["param"]
    rows = []
    for name, unit in zip(table["param"].values, units):
        row = table.sel(param=name)
        cells = [str(name), unit, *(float(row[v]) for v in ("mean", "sd", "q025", "q975", "rhat", "ess_bulk",
                                                            "geweke_z"))]
        if truth:
            known = name in truth
            cells += [truth[name] if known else float("nan"),
                      ("in" if row.q025 <= truth[name] <= row.q975 else "OUT") if known else ""]
        rows.append(cells)
    lines.append(Table(["parameter", "unit", "mean", "sd", "2.5 %", "97.5 %", "R-hat", "ESS-bulk", "Geweke z"]
                       + (["truth", "truth in 95 %"] if truth else []), rows,
                       units=["", "", "", "", "", "", "1", "1", "1"] + (["", ""] if truth else []),
                       title="Posterior summary: each parameter in its unit (mean, sd and interval)"))
    for block in noise["block"].values:
        row = noise.sel(block=block)
        lines.append(f"noise sigma {block}: {float(row['mean']):.4g} (95% [{float(row.q025):.4g}, "
                     f"{float(row.q975):.4g}])")
    for var in QOIS:
        if f"coverage_{var}" in bands:
            cover = ", ".join(f"{e} {100 * float(bands[f'coverage_{var}'].sel(experiment=e)):.0f}% "
                              f"(model only {100 * float(bands[f'model_coverage_{var}'].sel(experiment=e)):.0f}%)"
                              for e in bands["experiment"].values)
            lines.append(f"{round(100 * (bands.attrs['band_high'] - bands.attrs['band_low']))}% band coverage of "
                         f"{var}: {cover}")
    seconds = {node: result.seconds(node) for node in result.keys}
    lines.append("node seconds (when computed): " + ", ".join(f"{n} {s:.1f}" for n, s in seconds.items() if s))
    return lines


def held_out_coverage(bands, experiments=("BCF2", "BCF3"), variables=tuple(QOIS)) -> float:
    """Fraction of all finite held-out observations inside the predictive band (pooled over QoIs and experiments)."""
    inside = total = 0.0
    for var in variables:
        for e in experiments:
            n = float(bands[f"points_{var}"].sel(experiment=e))
            inside += n * float(bands[f"coverage_{var}"].sel(experiment=e))
            total += n
    return inside / total if total else np.nan
