"""Chapter-2 front end: every support-experiment fit -> ``priors`` -> the chapter-3 or chapter-4 calibration DAG.

The thesis's initial model calibration (Fig. 2.1, section 2.12, Algorithm 1 lines 4-5) as one cached DAG:

1. one node per lab fit (bundled synthetic tables by default, or your own files through ``paths``):
   ``fit_polymer_rheology`` -> ``fit_polymer_coreflood`` (which reuses the rheology estimates),
   ``fit_polymer_adsorption`` / ``fit_surfactant_adsorption`` (stage ``fit_adsorption``), ``fit_tracer``,
   ``fit_phase_behaviour``, ``fit_ift``, ``fit_me_viscosity``, ``fit_desaturation``;
2. ``space``: the ``priors`` stage -- ±20 % uniform boxes around the lab estimates of the thesis's uncertain
   parameters (Table 3.2 / 4.1 names), or ``mode="fit_uncertainty"`` boxes of ``k`` standard errors; parameters no
   lab test measures (GAMHF, the Corey exponents E2C/E2WC) keep the calibration table's ranges;
3. the front end (``history_matching`` or ``bayesian_calibration``) included unchanged with its own ``space`` node
   replaced by the priors (``Pipeline.include(..., share=["space"])``): its nodes are named ``<front_end>.<node>``.

    spflow run lab_priors --jobs 2
    spflow run lab_priors --quick      # the front end's quick profile
"""

from __future__ import annotations

import importlib
from pathlib import Path

import spflow
from spflow.plugins.design.thesis_tables import TABLE_3_2, TABLE_4_1

#: the front ends and the calibration table whose parameter names (and ranges for unfitted names) they use
FRONT_ENDS = {"history_matching": TABLE_3_2, "bayesian_calibration": TABLE_4_1}
#: the uncertain parameters of Tables 3.2/4.1 that no support experiment measures (their table ranges are kept)
UNFITTED = ("GAMHF", "E2C", "E2WC")
#: node -> (stage, extra params) of every lab fit; the port of ``priors`` each feeds is the node name
FITS = {
    "fit_polymer_rheology": ("fit_polymer_rheology", {}),
    "fit_polymer_coreflood": ("fit_polymer_coreflood", {}),
    "fit_polymer_adsorption": ("fit_adsorption", {"component": "polymer"}),
    "fit_surfactant_adsorption": ("fit_adsorption", {"component": "surfactant"}),
    "fit_tracer": ("fit_tracer", {}),
    "fit_phase_behaviour": ("fit_phase_behaviour", {}),
    "fit_ift": ("fit_ift", {}),
    "fit_me_viscosity": ("fit_me_viscosity", {}),
    "fit_desaturation": ("fit_desaturation", {}),
}


def _front_end(name: str):
    """The front-end pipeline module (the built-in ``spflow.pipelines.<name>``)."""
    return importlib.import_module(f"spflow.pipelines.{name}")


def pipeline(front_end: str | None = "history_matching", mode: str = "relative", relative: float = 0.2,
             k: float = 2.0, paths: dict[str, str] | None = None, study=None, profile: str = "study",
             quick: bool = False, **front_end_args) -> spflow.Pipeline:
    """Lab fits -> ``space`` (priors) [-> the ``front_end`` DAG built with ``front_end_args``].

    ``front_end``: "history_matching", "bayesian_calibration" or None (fits and priors only). ``paths``: fit node ->
    lab table path (default: the bundled synthetic tables). ``mode``/``relative``/``k``: see the ``priors`` stage.
    ``study``/``profile``: the front end's corefloods (default: the bundled study; see ``history_matching``).
    ``quick``: the front end's own quick profile (small budgets).
    """
    if front_end is not None and front_end not in FRONT_ENDS:
        raise ValueError(f"front_end must be one of {sorted(FRONT_ENDS)} or None, got {front_end!r}")
    paths = dict(paths or {})
    unknown = sorted(set(paths) - set(FITS))
    if unknown:
        raise ValueError(f"paths: unknown fit node {unknown[0]!r}; fit nodes: {sorted(FITS)}")
    table = FRONT_ENDS[front_end or "history_matching"]
    p = spflow.Pipeline("lab_priors")
    for node, (stage, params) in FITS.items():
        inputs = {"rheology": "fit_polymer_rheology"} if node == "fit_polymer_coreflood" else {}
        p.add(node, stage, params={**params, **({"path": paths[node]} if node in paths else {})}, inputs=inputs)
    p.add("space", "priors", inputs={node: node for node in FITS},
          params={"names": list(table), "ranges": {n: table[n] for n in UNFITTED}, "mode": mode,
                  "relative": relative, "k": k})
    if front_end is not None:
        front = _front_end(front_end).pipeline(quick=quick, study=study, profile=profile, **front_end_args)
        p.include(front, front_end, share=["space"])
    return p


def report(result: spflow.RunResult, outdir: Path) -> list[str]:
    """The goodness-of-fit figures of every lab fit (Figs. 2.2-2.9, adsorption isotherms) and the prior table (the
    front end's own figures come from its module's ``report`` on a run of that pipeline)."""
    from spflow.plugins.lab import polymer_fit_figures as fa
    from spflow.plugins.lab import surfactant_fit_figures as fb

    figures = [("fit_polymer_rheology", fa.polymer_rheology_figure, "fig_2_2_polymer_rheology"),
               ("fit_polymer_rheology", fa.half_shear_rate_figure, "fig_2_3_half_shear_rate"),
               ("fit_polymer_coreflood", fa.polymer_coreflood_figure, "fig_2_4_polymer_coreflood"),
               ("fit_phase_behaviour", fb.phase_behaviour_figure, "fig_2_5_phase_behaviour"),
               ("fit_ift", fb.ift_figure, "fig_2_6_ift"),
               ("fit_me_viscosity", fb.me_viscosity_figure, "fig_2_7_me_viscosity"),
               ("fit_desaturation", fb.desaturation_figure, "fig_2_8_desaturation"),
               ("fit_tracer", fa.tracer_figure, "fig_2_9_tracer"),
               ("fit_polymer_adsorption", fa.adsorption_figure, "polymer_adsorption"),
               ("fit_surfactant_adsorption", fa.adsorption_figure, "surfactant_adsorption")]
    written = [figure(result[node], outdir / f"{stem}.png") for node, figure, stem in figures]
    space = result["space"]
    space.to_netcdf(outdir / "priors.nc")
    lines = [f"wrote {len(written)} figures and priors.nc to {outdir}",
             "parameter   source                      estimate    prior box"]
    for name in space["param"].values:
        row = space.sel(param=name)
        lines.append(f"{name:<10}  {str(row.source.values):<26}  {float(row.default):<10.4g}  "
                     f"[{float(row.lower):.4g}, {float(row.upper):.4g}] {str(row.unit.values)}")
    return lines
