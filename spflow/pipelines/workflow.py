"""The main job: the thesis's whole workflow on a study's corefloods, one cached DAG, one HTML report.

Default study: the bundled BCF1-3 (BCF1 + BCF2 calibrate, BCF3 is held out); ``--study FILE`` runs it on yours, with
the study's roles deciding which corefloods train the proxies and calibrations and which are held out;
``--profile thesis`` is the thesis's BCF1-only training on the thesis's tables (see ``history_matching``).

1. ``screening.*``: Sobol' screening of the Table 3.1 sub-models on the first training coreflood (Fig. 3.2;
   pipeline ``screening``).
2. ``hm.*``: chapter 3 -- design over the study's calibrated parameters (``--profile thesis``: Table 3.2) ->
   simulator -> PCE -> NSGA-II on the training corefloods, checked on the held-out ones (Figs. 3.10-3.14; pipeline
   ``history_matching``).
3. ``proxy.*``: the chapter-3 proxies checked on independent simulator runs: the PCE and a PC-Kriging model on the
   same training runs (Figs. 3.4-3.5, 3.8, 3.15), and the PCE's convergence with the design size (Algorithm 2,
   Fig. 3.3).
4. ``bc.*``: chapter 4 -- design over the study's calibrated parameters (``--profile thesis``: Table 4.1) -> PCE ->
   MCMC -> posterior predictive on every observed coreflood (Apps. B-E, Figs. 4.4-4.5; pipeline
   ``bayesian_calibration``).
5. ``slug.*``: slug sizes designed under the posterior with EEIHV on the study's reference flood, oil price
   drifting up and down (Figs. 4.6-4.10; pipeline ``slug_design``).
6. ``gap.*``: where the calibrated model misses the data and which unmodelled effect explains it
   (pipeline ``gap_diagnosis``).

Nodes shared by several parts (the bundled observations, for one) are computed once; a part already run on its own
with the same settings comes from the cache. ``--quick`` runs the same DAG with small budgets (a first look).

    spflow run workflow --jobs 2            # complete run (see the README for measured times)
    spflow run workflow --quick --jobs 2    # quick profile
    spflow run workflow --study study.toml --quick
"""

from __future__ import annotations

import json
from pathlib import Path

import spflow
from spflow.pipelines import bayesian_calibration, gap_diagnosis, history_matching, screening, slug_design
from spflow.study.pipeline_inputs import resolve_study


def proxy_check(p: spflow.Pipeline, samples: int = 100, cells: int = 100, seed: int = 7) -> None:
    """Nodes ``proxy.*``: a PC-Kriging model on the chapter-3 training runs, and independent LHS validation runs
    scoring it and the PCE (Eq. 3.15)."""
    hm_inputs = dict(p.nodes["hm.surrogate"].inputs)
    proxy = {k: v for k, v in p.nodes["hm.surrogate"].params.items() if k in ("variables", "experiments")}
    p.add("proxy.pck", "pck", inputs=hm_inputs, params=proxy)
    p.add("proxy.design", "lhs_design", inputs={"space": hm_inputs["space"]}, params={"samples": samples, "seed": seed})
    model = {k: v for k, v in p.nodes["hm.responses"].params.items() if k in ("experiments", "fixed", "effects")}
    p.add("proxy.responses", "forward", inputs={"design": "proxy.design"}, params={**model, "cells": cells})
    for kind, node in (("pce", "hm.surrogate"), ("pck", "proxy.pck")):
        p.add(f"proxy.validation_{kind}", "surrogate_validation",
              inputs={"surrogate": node, "design": "proxy.design", "responses": "proxy.responses"})
    p.add("proxy.adaptive", "adaptive_pce", inputs={"space": hm_inputs["space"]},
          params={**proxy, **model, "cells": cells, "n_initial": samples // 2, "n_increment": samples // 2,
                  "n_max": 2 * samples, "seed": seed + 1})


def pipeline(study=None, profile: str = "study", quick: bool = False) -> spflow.Pipeline:
    """The whole workflow on ``study`` (a study file, a :class:`~spflow.study.Study`, or ``None``: the bundled
    study), read once; ``profile``: ``"study"`` (roles) or ``"thesis"``; ``quick``: every part's small-budget
    profile."""
    study = resolve_study(study)
    p = spflow.Pipeline("workflow_quick" if quick else "workflow")
    p.include(screening.pipeline(quick=quick, study=study), "screening")
    p.include(history_matching.pipeline(quick=quick, study=study, profile=profile), "hm")
    proxy_check(p, **({"samples": 40, "cells": 40} if quick else {}))
    p.include(bayesian_calibration.pipeline(quick=quick, study=study, profile=profile), "bc")
    slug_design.add_design_nodes(p, "bc.posterior", prefix="slug.", study=study, quick=quick)
    p.include(gap_diagnosis.pipeline(quick=quick, study=study), "gap")
    return p


def _proxy_report(result: spflow.RunResult, outdir: Path) -> list[str]:
    """Both chapter-3 proxies on the independent runs (Figs. 3.3-3.5, 3.8, 3.15): R^2 of the final and maximum
    values, Eq. 3.15 errors."""
    from spflow.plugins.surrogates import figures

    pce, pck = result["hm.surrogate"], result["proxy.pck"]
    design, runs = result["proxy.design"], result["proxy.responses"]
    figures.convergence_figure(result["proxy.adaptive"], outdir / "fig_3_3_pce_convergence.png")
    experiment = str(runs["experiment"].values[0])  # the first training coreflood
    figures.proxy_vs_simulator_figure({"PCE": pce, "PC-Kriging": pck}, design, runs,
                                      outdir / "fig_3_4_proxy_vs_simulator.png", experiment=experiment)
    figures.moments_figure(pce, runs, outdir / "fig_3_8_pce_moments.png", experiment=experiment)
    schedule = json.loads(json.loads(result["hm.observations"].attrs["coreflood_attrs"])[experiment]["schedule"])
    figures.band_figure(pck, design, runs, outdir / "fig_3_15_pck_band.png", reference=pce, experiment=experiment,
                        schedule=schedule)
    lines = [f"{'proxy':6s} {'QoI':18s} {'R2 final':>9s} {'R2 max':>9s} {'median R2 (per PV)':>19s} "
             f"{'mean err':>9s} {'var err':>9s}   (Eq. 3.15, independent LHS runs of the training corefloods)"]
    for kind in ("pce", "pck"):
        val = result[f"proxy.validation_{kind}"]
        for q in range(val.sizes["qoi"]):
            row = val.isel(qoi=q)
            variable, exp = str(row["qoi_variable"].values), str(row["qoi_experiment"].values)
            r2 = val["r2"].where((val["output_variable"] == variable) & (val["output_experiment"] == exp)).median()
            lines.append(f"{kind:6s} {variable + ':' + exp:18s} {float(row['r2_final']):9.4f} "
                         f"{float(row['r2_max']):9.4f} "
                         f"{float(r2):19.4f} {float(row['mean_l2_error']):9.2e} {float(row['variance_l2_error']):9.2e}")
    return lines


def report(result: spflow.RunResult, outdir: Path) -> dict[str, list]:
    """One section per part (sub-directories of ``outdir``), each written by that part's own report."""
    sections = {}
    for prefix, module in (("screening", screening), ("hm", history_matching), ("bc", bayesian_calibration),
                           ("slug", slug_design), ("gap", gap_diagnosis)):
        part = module.__name__.rpartition(".")[2]
        sub = outdir / part
        sub.mkdir(parents=True, exist_ok=True)
        sections[part] = module.report(result.scoped(prefix), sub)
    proxies = outdir / "proxy_validation"
    proxies.mkdir(exist_ok=True)
    sections["proxy_validation"] = _proxy_report(result, proxies)
    return dict(sorted(sections.items(), key=lambda kv: _ORDER.index(kv[0])))


_ORDER = ["screening", "history_matching", "proxy_validation", "bayesian_calibration", "slug_design", "gap_diagnosis"]
