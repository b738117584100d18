"""The next experiment after a diagnosis (issue 20, item 3): when the verdict leaves candidates that the data do not
tell apart, or a gap that candidates close on the calibration data but cannot be attributed (weakly identified
effects), rank lab-runnable corefloods by how well they would separate them and write the best one out.

The competing hypotheses are the diagnosis's own refits of the members of its final ambiguity set (the last step
that refitted them: "reference + effect", each with the linearised covariance of its calibration), or, for an
``unattributed`` verdict, the base model itself against the refits of the candidates that close the gap
(:func:`competing_fits`); the reference
coreflood, whose core, rate and measurement chain the new coreflood keeps, is the first calibration coreflood; the
diagnosis's numerical-error term (its estimated scale, at the calibrated base point) is in the designer's error model
as in the diagnosis's. The ranking is :func:`~spflow.plugins.gap.next_experiment.rank_designs` over
:func:`~spflow.plugins.gap.design_space.design_space` (slug sizes and concentrations, a salinity change, a long
post-flush, per-slug injection-rate steps); ``docs/next_experiment.md`` has the method.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import xarray as xr

from spflow.study.proposed_experiment import study_experiment_toml

from .diagnosis import GapDiagnosis
from .next_experiment import hypotheses_from_fits, rank_designs
from .numerical_error import NumericalTerm
from .proposal import proposal_summary, write_proposal

__all__ = ["NextExperiment", "competing_fits", "hypotheses_source", "accuracy_caveat", "propose_next_experiment",
           "BASE_HYPOTHESIS", "MAX_UNATTRIBUTED"]


@dataclass(frozen=True)
class NextExperiment:
    """The ranked designs, the best one's rationale and the files written for it."""

    table: xr.Dataset
    summary: dict
    files: dict[str, Path]

    def lines(self) -> list[str]:
        """What ``spflow diagnose`` prints about the proposal."""
        s = self.summary
        accuracy = ", ".join(f"{k} {v:.2f}" for k, v in s["accuracy"].items() if v is not None)
        out = [f"next experiment (separates {', '.join(s['hypotheses'])}; "
               f"{s['assumptions'].get('hypotheses_source', 'hypotheses given')}): {s['label']} ({s['kind']}, "
               f"{s['total_pv']:.3g} PV)",
               f"  predicted decision accuracy if each is true: {accuracy}; worst expected log predictive ratio "
               f"{s['worst_expected_log_ratio_nat']:.3g} nat"]
        if "accuracy_caveat" in s["assumptions"]:
            out.append(f"  caution: {s['assumptions']['accuracy_caveat']}")
        out += [f"  runner-up: {r['label']} (worst accuracy {r['worst_accuracy']:.2f})" for r in s["runners_up"][:2]
                if r["worst_accuracy"] is not None]
        out += [f"  wrote {path}" for path in self.files.values()]
        return out


#: hypothesis name of the base model itself (no catalogued effect added) when an unattributed gap is separated
BASE_HYPOTHESIS = "base"
#: the most candidates an unattributed gap's proposal separates from the base (the closers with the best held-out
#: scores; each hypothesis costs ``truth_draws`` forward runs per design)
MAX_UNATTRIBUTED = 3


def competing_fits(diag: GapDiagnosis) -> dict:
    """The competing calibrated models (name -> Fit) a next experiment should separate:

    * an ambiguity set of two or more candidates: the refits of its members, from the last step that refitted them
      all;
    * an ``unattributed`` gap (the candidates ``diag.closers`` close half the calibration gap but none predicts the
      held-out coreflood well enough to be declared, i.e. weakly identified): the base model itself
      (:data:`BASE_HYPOTHESIS`) and the first step's refits of the first :data:`MAX_UNATTRIBUTED` closers;

    empty otherwise (nothing to separate; ``verdict.verdict`` returns ``unattributed`` only with closers)."""
    if diag.verdict == "unattributed" and diag.closers:
        names = diag.closers[:MAX_UNATTRIBUTED]
        return {BASE_HYPOTHESIS: diag.base_fit} | {n: diag.steps[0].fits[n] for n in names}
    names = list(diag.ambiguity)
    if len(names) < 2:
        return {}
    for step in reversed(diag.steps):
        if all(n in step.fits for n in names):
            return {n: step.fits[n] for n in names}
    return {}


def hypotheses_source(diag: GapDiagnosis) -> str:
    """Where :func:`competing_fits` took the hypotheses from, naming any closer it left out (recorded in the
    proposal's assumptions and printed)."""
    if diag.verdict != "unattributed":
        return "the diagnosis's final ambiguity set"
    left = diag.closers[MAX_UNATTRIBUTED:]
    return (f"unattributed gap: the base model against the first {min(len(diag.closers), MAX_UNATTRIBUTED)} of the "
            f"{len(diag.closers)} candidates that close it (best held-out score first)"
            + (f"; left out: {', '.join(left)}" if left else ""))


def accuracy_caveat(diag: GapDiagnosis) -> str | None:
    """What the predicted accuracies cannot promise for ``diag``'s verdict (recorded in the proposal's assumptions
    and printed), or ``None``. After an ``unattributed`` verdict the calibration data pin the base parameters
    weakly (the refit with the true effect can land elsewhere in a flat valley), and the designer holds each
    hypothesis at its calibrated parameters: in the twin studies the realised accuracy after such verdicts was about
    half the predicted one, much further off than after ambiguous verdicts (docs/next_experiment.md)."""
    if diag.verdict != "unattributed":
        return None
    return ("the predicted accuracies hold each model at its calibrated parameters, which the calibration data pin "
            "weakly after an unattributed verdict; the realised accuracy can be far lower (docs/next_experiment.md)")


def propose_next_experiment(diag: GapDiagnosis, directory, *, parallel=None, log=None) -> NextExperiment | None:
    """Rank the next corefloods for ``diag``'s competing hypotheses (:func:`competing_fits`) and write the best one
    into ``directory``:
    ``next_experiment.toml`` (schedule file), ``next_experiment.json`` (rationale) and
    ``next_experiment_study.toml`` (a predict-role study experiment on the reference core). ``None`` when the
    verdict leaves nothing to separate."""
    fits = competing_fits(diag)
    if not fits:
        return None
    reference = diag.calibration[0]
    variables = [v for v in diag.options.variables if v in reference.observed]
    scale = diag.numerical_scale.estimate if diag.numerical_scale is not None else 0.0
    numerical = (NumericalTerm(diag.base_fit, tuple(diag.options.numerical_variants), scale,
                               diag.options.numerical_window) if scale > 0.0 else None)
    table = rank_designs(hypotheses_from_fits(fits), diag.base, reference, variables=variables,
                         min_delta=diag.options.rule.min_delta, se_factor=diag.options.rule.se_factor,
                         numerical=numerical, parallel=parallel, log=log)
    table.attrs["hypotheses_source"] = hypotheses_source(diag)
    if (caveat := accuracy_caveat(diag)) is not None:
        table.attrs["accuracy_caveat"] = caveat
    files = write_proposal(table, directory)
    text, _ = study_experiment_toml("next_experiment", files["schedule"].name, reference.core,
                                    reference.measurement, reference.name)
    files["study_experiment"] = Path(directory) / "next_experiment_study.toml"
    files["study_experiment"].write_text(text + "\n", encoding="utf-8")
    return NextExperiment(table, proposal_summary(table), files)
