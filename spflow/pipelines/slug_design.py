"""Slug-size design under uncertainty (thesis §4.7) downstream of the chapter-4 Bayesian calibration.

The reference flood is the study's (default: the bundled study): its first ``calibration`` experiment with a
surfactant slug (else the first experiment with one) gives the core, rate and fluids of every simulated design and,
through its SP slug and polymer drive, the reference concentrations and slug sizes of Eq. 4.10 (bundled: BCF1).
``reference="thesis"`` keeps Table 4.2's reference slugs (0.25 PV of 6 780 ppm surfactant / 2 500 ppm polymer) on
the reference flood's core.

The ``bayesian_calibration`` DAG (forward model -> design -> PCE proxy -> MCMC posterior; see that pipeline) is
included unchanged under the prefix ``bc.`` (its cached results are reused), and two ``slug_design`` nodes read its
posterior ``bc.posterior``: EEIHV on (-NPV, max Δp) over the slug sizes (s_htds, s_sp, s_p) with the oil price
drifting up (``design_up``, μ = +1e-5 per step) and down (``design_down``, μ = -1e-5).

    spflow run slug_design --jobs 2 --until design_up --until design_down   # skips the predictive bands

``report`` writes Figs. 4.6-4.10, the two result Datasets and a summary (knee designs, fronts, stopping).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

import spflow
from spflow.pipelines import bayesian_calibration
from spflow.study.pipeline_inputs import StudyInputs

DRIFTS = {"design_up": 1.0e-5, "design_down": -1.0e-5}
LABELS = {"design_up": "positive drift", "design_down": "negative drift"}
#: ``reference`` values: the study's reference flood, or Table 4.2's reference slugs
REFERENCES = ("study", "thesis")


def pipeline(max_iter: int = 100, n_init: int = 20, batch: int = 1, cells: int = 100, knee_draws: int = 50,
             steps_per_year: int = 365, seed: int = 2024, study=None, profile: str = "study",
             reference: str = "study", quick: bool = False) -> spflow.Pipeline:
    """The calibration DAG as ``bc.*`` (on ``study`` under ``profile``) plus the two slug-design nodes;
    ``reference``: see the module docstring; ``quick``: small budgets everywhere."""
    p = spflow.Pipeline("slug_design_quick" if quick else "slug_design")
    p.include(bayesian_calibration.pipeline(quick=quick, study=study, profile=profile), "bc")
    add_design_nodes(p, "bc.posterior", max_iter=max_iter, n_init=n_init, batch=batch, cells=cells,
                     knee_draws=knee_draws, steps_per_year=steps_per_year, seed=seed, study=study,
                     reference=reference, quick=quick)
    return p


def add_design_nodes(p: spflow.Pipeline, posterior: str, *, prefix: str = "", max_iter: int = 100, n_init: int = 20,
                     batch: int = 1, cells: int = 100, knee_draws: int = 50, steps_per_year: int = 365,
                     seed: int = 2024, study=None, reference: str = "study", quick: bool = False) -> None:
    """The nodes ``<prefix>design_up`` and ``<prefix>design_down`` reading the posterior node ``posterior``, on the
    reference flood of ``study`` (a study file, a Study, or ``None``: the bundled study)."""
    if reference not in REFERENCES:
        raise spflow.ParameterError(f"slug_design: reference {reference!r} is not one of {list(REFERENCES)}")
    if quick:
        max_iter, n_init, cells, knee_draws = 8, 8, 40, 10
    inputs = StudyInputs.of(study)
    flood = inputs.reference_flood()
    model = {"fixed": dict(inputs.study.fixed, **flood.model_params()), "effects": dict(inputs.study.effects),
             "reference_flood": dict(flood.forward_experiment()["schedule"], name=flood.name) if reference == "study"
             else {}}
    for node, drift in DRIFTS.items():
        p.add(prefix + node, "slug_design", inputs={"posterior": posterior},
              params={"drift": drift, "steps_per_year": steps_per_year, "n_init": n_init, "max_iter": max_iter,
                      "batch": batch, "cells": cells, "knee_draws": knee_draws, "seed": seed,
                      "snapshots": [1, max(1, max_iter // 2)], **model})


def summary(results: dict) -> list[str]:
    """Knee designs, fronts and run statistics of the slug-design nodes in ``results`` {node: Dataset}."""
    lines = []
    for node, ds in results.items():
        knee = ds["knee_design"].values
        front = np.flatnonzero(ds["on_front"].values)
        proj = ds["projected"].values
        lines.append(f"{LABELS.get(node, node)} (μ = {ds.attrs['drift']:+.0e}/step, {ds.attrs['steps_per_year']} "
                     f"steps/year, {100 * (np.exp(ds.attrs['annual_log_drift']) - 1):+.2f} %/year): "
                     f"{ds.sizes['evaluation']} evaluations, {ds.sizes['iteration']} iterations, stop "
                     f"{ds.attrs['stop_reason']}, {front.size} designs on the projected front")
        lines.append("  knee design: " + ", ".join(f"{n} = {v:.2f} PV" for n, v in zip(ds["design_var"].values, knee))
                     + f"; E[NPV] = {-float(ds['knee_projected'][0]):.3f} M$, E[max dp] = "
                       f"{float(ds['knee_projected'][1]):.2f} kPa (GP means)")
        npv = ds["knee_npv"].values
        lines.append(f"  knee over {npv.size} draws: NPV median {np.median(npv):.3f} M$ (5-95 % "
                     f"{np.quantile(npv, 0.05):.3f} .. {np.quantile(npv, 0.95):.3f}), max dp median "
                     f"{np.median(ds['knee_max_dp'].values):.2f} kPa")
        lines.append("  front (s_htds, s_sp, s_p | E[NPV] M$, E[max dp] kPa):")
        for i in front[np.argsort(proj[front, 0])]:
            x = ds["design"].values[i]
            lines.append(f"    {x[0]:.2f} {x[1]:.2f} {x[2]:.2f} | {-proj[i, 0]:.3f} {proj[i, 1]:.2f}")
        top = front[np.argmin(proj[front, 0])]
        lines.append("  best-NPV front design: " + ", ".join(
            f"{n} = {v:.2f}" for n, v in zip(ds["design_var"].values, ds["design"].values[top])))
    return lines


def report(result: spflow.RunResult, outdir: Path) -> list[str]:
    """Figs. 4.6-4.10, the result Datasets (``design_up.nc``, ``design_down.nc``) and the summary."""
    from spflow.plugins.slug_design import figures as fig

    outdir = Path(outdir)
    results = {node: result[node] for node in DRIFTS}
    for node, ds in results.items():
        ds.to_netcdf(outdir / f"{node}.nc")
    written = [fig.plot_price_paths({LABELS[n]: ds for n, ds in results.items()}, outdir / "fig_4_6_price.png")]
    for number, node in (("4_7", "design_up"), ("4_8", "design_down")):
        written.append(fig.plot_front_evolution(results[node], outdir / f"fig_{number}_front_{node}.png",
                                                f"Fig. {number.replace('_', '.')}: Pareto front, {LABELS[node]}"))
    for number, node in (("4_9", "design_up"), ("4_10", "design_down")):
        written.append(fig.plot_knee_design(results[node], outdir / f"fig_{number}_knee_{node}.png",
                                            f"Fig. {number.replace('_', '.')}: knee design, {LABELS[node]}"))
    reference = next(iter(results.values())).attrs.get("reference_concentrations", "Table 4.2")
    return [f"wrote {len(written)} figures and {len(results)} Datasets to {outdir}",
            f"reference flood: {reference}", *summary(results)]
