"""Chapter-3 history matching: forward model -> (screening) -> design -> PCE proxy -> NSGA-II -> held-out validation.

The thesis's §3.3-3.7 as one cached DAG on a study's corefloods (default: the bundled study, BCF1-3):

1. ``space``: the study's calibrated parameters (``[parameters.calibrated]``: one design column per label, which may
   set several UTCHEM names, e.g. ``n_high`` = the Corey exponents ``E1C``-``E3C``; the bundled study: the Table 3.2
   ranges with n_high / n_low moving all three phases' exponents, as its data's truth does); ``profile="thesis"``:
   thesis Table 3.2 as the thesis pipeline used it (n_high / n_low = the oleic exponents ``E2C`` / ``E2WC``).
   Optionally ``screening`` (Sobol' indices on the forward model) and ``screened_space`` (the parameters it keeps)
   in front of the design.
2. ``design`` (Latin hypercube, N_s points) -> ``responses`` (simulator on the training corefloods, each with its own
   core, rate and schedule).
3. ``surrogate``: the ``pce`` stage on dp and recovery of the training corefloods, hybrid LARS up to degree 5 (swap
   in PC-Kriging with ``p.set_stage("surrogate", "pck", {...})``; every surrogate stage has the same inputs and
   output).
4. ``observations`` (measured data on the simulator grid) -> ``calibration`` (``nsga2_calibration``: objectives of
   Eq. 3.17 on the surrogate, summed over the training corefloods; Algorithm 3's checks on the held-out ones with
   the simulator; the parameters the training data leave undetermined are named with a warning).
5. ``pareto_sets`` (the Pareto sets after the first and the last generation, one design) -> ``validation``
   (simulator on every observed coreflood at all of them) for Figs. 3.11-3.13.

Roles come from the study: ``calibration`` experiments train, ``heldout`` ones are held out (the bundled study: BCF1
+ BCF2 train, BCF3 is held out). ``profile="thesis"`` is the thesis's set-up instead: the thesis's Table 3.2 space,
the first calibration experiment alone trains (BCF1) and every other observed one is held out (BCF2, BCF3); BCF1
leaves HBNC71 undetermined, so the held-out fit of BCF2/BCF3 is not constrained there (docs/calibration.md).

Every node is cached by provenance: changing only the GA's settings (e.g. ``generations``) reruns ``calibration``
and what follows it, nothing upstream.

    spflow run history_matching --jobs 2
    spflow run history_matching --study study.toml --quick
    spflow run history_matching --profile thesis
"""

from __future__ import annotations

from pathlib import Path

import spflow
from spflow.core.report_table import Table
from spflow.plugins.design.thesis_tables import TABLE_3_2
from spflow.study.pipeline_inputs import StudyInputs

#: ``profile`` values: the study's roles and parameter space, or the thesis's single training coreflood and tables.
PROFILES = ("study", "thesis")


def space_params(inputs: StudyInputs, profile: str, table: dict) -> dict:
    """The ``parameter_space`` stage's parameters under ``profile``: the study's calibrated parameters, or
    (``"thesis"``) the thesis's ``table`` (Table 3.2 for chapter 3, Table 4.1 for chapter 4)."""
    if profile not in PROFILES:
        raise spflow.ParameterError(f"profile {profile!r} is not one of {list(PROFILES)}")
    return {"names": list(table), "ranges": table} if profile == "thesis" else inputs.space()


def study_inputs(study=None, profile: str = "study") -> StudyInputs:
    """The study's training and held-out experiments under ``profile`` (``"study"``: the roles; ``"thesis"``: the
    first calibration experiment trains, every other observed experiment is held out)."""
    if profile not in PROFILES:
        raise spflow.ParameterError(f"history_matching: profile {profile!r} is not one of {list(PROFILES)}")
    inputs = StudyInputs.of(study)
    if profile == "thesis":
        first, rest = inputs.training[0], inputs.training[1:] + inputs.heldout
        inputs = StudyInputs.of(inputs.study, training=[first.name], heldout=[e.name for e in rest])
    if not inputs.heldout:
        raise spflow.ParameterError(
            f"history_matching: study {inputs.study.path}: no held-out experiment (role 'heldout') to cross-validate "
            f"the Pareto set on (Algorithm 3); give one of {inputs.training_names} role 'heldout'")
    return inputs


def pipeline(samples: int = 200, cells: int = 100, generations: int = 100, population: int = 120,
             degree_max: int = 5, solver: str = "lars", seed: int = 2024, screening: bool = False,
             study=None, profile: str = "study", observed: list[str] | None = None,
             quick: bool = False) -> spflow.Pipeline:
    """The chapter-3 DAG on ``study`` (a study file, a :class:`~spflow.study.Study`, or ``None``: the bundled
    study). ``profile``: ``"study"`` (roles, the study's space) or ``"thesis"`` (BCF1-only training, Table 3.2);
    ``observed``: coreflood files
    replacing the study's data (their ``experiment`` attrs must be the study's names, e.g. synthetic twins);
    ``screening``: put a Sobol' screening of the space in front of the design; ``quick``: small budgets."""
    if quick:
        samples, cells, generations, population, degree_max = 60, 40, 20, 40, 3
    inputs = study_inputs(study, profile)
    train = inputs.forward(inputs.training)
    model = {"cells": cells, **inputs.model()}
    p = spflow.Pipeline("history_matching_quick" if quick else "history_matching")
    p.add("space", "parameter_space", params=space_params(inputs, profile, TABLE_3_2))
    space = "space"
    if screening:
        p.add("screening", "sobol_screening", inputs={"space": "space"},
              params={"experiments": train[:1], "samples": 32, "seed": seed, **model})
        p.add("screened_space", "selected_space", inputs={"screening": "screening"})
        space = "screened_space"
    p.add("design", "lhs_design", inputs={"space": space}, params={"samples": samples, "seed": seed})
    p.add("responses", "forward", inputs={"design": "design"}, params={"experiments": train, **model})
    p.add("surrogate", "pce", inputs={"space": space, "design": "design", "responses": "responses"},
          params={"variables": ["dp", "recovery"], "experiments": inputs.training_names, "degree_max": degree_max,
                  "solver": solver})
    p.add("observations", "observations",
          params={"experiments": list(observed) if observed else inputs.observations(inputs.observed)})
    p.add("calibration", "nsga2_calibration",
          inputs={"surrogate": "surrogate", "observations": "observations", "space": space},
          params={"training": inputs.training_names, "held_out": inputs.forward(inputs.heldout),
                  "population": population, "generations": generations, "n_cross": 50, "seed": seed, **model})
    p.add("pareto_sets", "pareto_design", inputs={"calibration": "calibration"}, params={"generations": [1, 0]})
    p.add("validation", "forward", inputs={"design": "pareto_sets"},
          params={"experiments": inputs.forward(inputs.observed), **model})
    return p


def report(result: spflow.RunResult, outdir: Path, truth: dict[str, float] | None = None) -> list[str | Table]:
    """Figs. 3.10-3.14, the calibration Dataset, and a summary (σ_loss, misfits, ranges, node timings)."""
    from spflow.plugins.calibration.pareto_figures import plot_fronts, plot_history_match, plot_parameter_ranges

    cal, observations = result["calibration"], result["observations"]
    cal.to_netcdf(outdir / "calibration.nc")
    written = [plot_fronts(cal, outdir / "fig_3_10_pareto_fronts.png")]
    for k, experiment in enumerate(str(e) for e in result["validation"]["experiment"].values):
        written.append(plot_history_match(result["validation"], result["pareto_sets"], observations, experiment,
                                          outdir / f"fig_3_{11 + k}_{experiment}.png"))
    written.append(plot_parameter_ranges(cal, outdir / "fig_3_14_parameter_ranges.png", truth=truth))
    lines = [f"wrote {len(written)} figures and calibration.nc to {outdir}",
             f"stopped after {cal.attrs['generations_run']} generations: {cal.attrs['stop_reason']}",
             f"final Pareto set: {cal.sizes['pareto']} points"]
    for g in cal["checkpoint"].values:
        per = cal["checkpoint_misfit"].sel(checkpoint=g)
        detail = ", ".join(f"{e}/{v} {float(per.sel(experiment=e, objective=v)):.4f}"
                           for e in per["experiment"].values for v in per["objective"].values)
        lines.append(f"generation {int(g)}: sigma_loss = {float(cal['sigma_loss'].sel(checkpoint=g)):.4f} ({detail})")
    lines.append(f"held-out misfit over the {cal.attrs['heldout_consistent_count']} of {cal.sizes['pareto']} Pareto "
                 f"points the training data do not reject against the front's best: "
                 f"{cal.attrs['sigma_loss_consistent']:.4f} (whole front, Algorithm 3: {cal.attrs['sigma_loss_final']:.4f})")
    if "front_outside_region_warning" in cal.attrs:
        lines.append(f"note: {cal.attrs['front_outside_region_warning']}")
    level = f"{cal.attrs['confidence_level']:.0%}"
    lines.append(Table(
        ["parameter", "unit", "prior low", "prior high", "Pareto low", "Pareto high", f"noise-consistent low ({level})",
         f"noise-consistent high ({level})"],
        [[str(name), str(unit), *(float(cal[v].sel(param=name)) for v in (
            "prior_lower", "prior_upper", "calibrated_lower", "calibrated_upper", "confidence_lower",
            "confidence_upper"))] for name, unit in zip(cal["param"].values, cal["param_unit"].values)],
        title=f"Parameter ranges: prior, calibrated (Pareto set) and noise-consistent ({level} likelihood-ratio "
              "region); each row in its parameter's unit"))
    if "confidence_warning" in cal.attrs:
        lines.append(f"noise-consistent ranges: {cal.attrs['confidence_warning']}")
    if cal.attrs.get("undetermined_warning"):
        lines.append(f"WARNING: {cal.attrs['undetermined_warning']}")
    else:
        lines.append(f"every calibrated parameter is determined by the training data ({cal.attrs['training']}): no "
                     f"noise-consistent range covers {cal.attrs.get('undetermined_fraction', 0.9):.0%} of its prior")
    seconds = {node: result.seconds(node) for node in result.keys}
    lines.append("node seconds (when computed): " + ", ".join(f"{n} {s:.1f}" for n, s in seconds.items() if s))
    return lines
