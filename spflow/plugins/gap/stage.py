"""The ``diagnose`` stage: measured corefloods + base model + effect catalogue -> gap report Dataset.

The stage reads its corefloods itself (bundled names or files, like the ``observations`` stage: the measurement
model in their attrs is part of the prediction operator and of the error model) and keys its cache entry on their
content. The optional input ``calibrated`` plugs in an upstream calibration (a Pareto set or posterior sample on
dims (sample, param), e.g. from ``nsga2_calibration`` or ``emcee_sampler``) instead of the stage's own
least-squares calibration (:mod:`~spflow.plugins.gap.base_calibration`).
"""

from __future__ import annotations

import sys

from typing import TYPE_CHECKING

import xarray as xr

from spflow.core.errors import ParameterError
from spflow.core.hashing import canonical_hash
from spflow.core.params import Param
from spflow.core.schema import DatasetSchema, Variable
from spflow.core.stage import Stage, StageContext
from spflow.io.observed_source import load_observed, source_label
from spflow.plugins.design.schemas import DESIGN
from spflow.plugins.forward.numba_cache import source_digest

from .base_model import TABLE_3_2_BASE, BaseModel
from .catalogue import MAX_EFFECTS, candidates_for
from .observed import MEASURABLE
from .verdict import Rule

if TYPE_CHECKING:
    from .diagnosis import GapDiagnosis, Options

__all__ = ["Diagnose", "GAP_REPORT", "OPTION_PARAMS", "options_from"]

#: Schema of the gap report (:mod:`spflow.plugins.gap.report`).
GAP_REPORT = DatasetSchema(
    dims=("model", "experiment", "pv", "cell", "candidate", "step", "param"),
    variables={
        "cell_chi2": Variable(("model", "cell"), units="1", long_name="chi-square of each residual cell"),
        "gap_rank": Variable(("cell",), kind="i", units="1", long_name="rank of the cell by misfit"),
        "screen_z": Variable(("step", "candidate"), units="1", allow_nan=True, long_name="screening z-score"),
        "delta_elpd": Variable(("step", "candidate"), units="1", allow_nan=True,
                               long_name="change of expected log predictive density (nats)"),
        "fingerprint_cos": Variable(("candidate", "candidate_b"), units="1", long_name="cosine of two fingerprints"),
        "theta": Variable(("model", "param"), units_variable="param_units",
                          long_name="calibrated parameters of each model"),
        "param_units": Variable(("param",), kind="U", long_name="UDUNITS unit of each calibrated parameter"),
        "chi2_base": Variable((), units="1", long_name="chi-square of the base model"),
    },
    attrs=("verdict", "ambiguity_set", "effects", "final_model"),
    doc="gap report: localisation, candidate scores, verdict, gap closed",
)

#: Stage parameters that are diagnosis options (also accepted in the [diagnosis] table of a CLI base file).
OPTION_PARAMS = {
    "variables": Param(list, ["dp", "oil_cut"], choices=list(MEASURABLE),
                       doc="QoIs in the likelihood (recovery repeats the oil-cut readings: use one of the two)"),
    "pv_step": Param(float, 0.1, bounds=(0.01, 1.0), unit="PV",
                     doc="grid step (a multiple of the transducer interval keeps the AR(1) model exact)"),
    "alpha": Param(float, 0.01, bounds=(1e-6, 0.5), doc="significance level of the calibration-gap test and cells"),
    "shortlist": Param(int, 3, bounds=(1, 20), doc="candidates refitted per step (plus ambiguity partners)"),
    "first_step_refits": Param(str, "all", choices=["all", "shortlist"],
                               doc="first step: refit every candidate (screen order), or the screen's shortlist"),
    "expand_shortlist": Param(bool, True, doc="first step with first_step_refits = shortlist: while the gap is "
                                              "significant and no refit passes, refit the next candidates in "
                                              "screen order (shortlist at a time)"),
    "max_effects": Param(int, 2, bounds=(1, MAX_EFFECTS),
                         doc="effects in the final model at most (greedy and joint search; 3 finds three "
                             "coexisting effects)"),
    "subset_pool": Param(int, 4, bounds=(1, 8),
                         doc="shortlisted effects whose subsets (up to max_effects) are refitted jointly"),
    "numerical_error": Param(bool, True, doc="add the base model's own numerical error (2x cells; 2x cells "
                                             "upwind) to the error model"),
    "numerical_scale_max": Param(float, 1.0, bounds=(0.0, 10.0),
                                 doc="cap of the numerical-error scale, which is estimated from the base model's "
                                     "calibration residuals (0: the term is off)"),
    "discrepancy_degree": Param(int, 2, bounds=(0, 6),
                                doc="degree of the per-slug Legendre discrepancy competitor"),
    "max_nfev": Param(int, 30, bounds=(2, 1000), doc="least-squares iterations per fit"),
    "first_round_jacobian": Param(str, "difference", choices=["difference", "secant"],
                                  doc="Jacobians of the first round of a multi-start fit (refits): a forward "
                                      "difference at every step, or Broyden updates from one forward difference "
                                      "per start, the declared final model then refitted with forward "
                                      "differences (0.4-0.45 of the forward runs; changes results)"),
    "heldout_predictive": Param(str, "sampled", choices=["laplace", "sampled"],
                                doc="the held-out coreflood's predictive under each calibrated model: linearised at "
                                    "the optimum, or the posterior predictive sampled from predictive_draws draws "
                                    "(integrates over flat parameter valleys; ~2 x predictive_draws forward runs "
                                    "per scored model; leave-one-slug-out scores are always linearised)"),
    "predictive_draws": Param(int, 100, bounds=(20, 10000),
                              doc="draws of the sampled held-out predictive (heldout_predictive = sampled)"),
    "predictive_centre": Param(str, "newton", choices=["optimum", "newton"],
                               doc="mean of the sampled predictive's proposal: the minimiser of the Gauss-Newton "
                                   "model of the calibration chi2 at the calibrated optimum, or the optimum itself"),
    "starts": Param(int, 1, bounds=(1, 50), doc="base-calibration starts (defaults + Latin-hypercube points)"),
    "path_reruns": Param(int, 0, bounds=(0, 5),
                         doc="reruns of the whole diagnosis along other optimiser paths (difference step x1.1, "
                             "x0.9, ...) to show whether the verdict holds; each costs about one diagnosis"),
    "nuisance_scale": Param(float, 0.5, bounds=(1e-3, 1e3),
                            doc="prior scale of calibrated-parameter shifts in the unit box (projection, Laplace)"),
    "replicates": Param(int, 200, bounds=(10, 100000), doc="replicated data sets of the signature checks"),
    "max_lag": Param(float, 1.5, bounds=(0.0, 10.0), unit="PV",
                     doc="largest lag of the residual/input cross-correlation (effluent lags its slug ~1 PV)"),
    "seed": Param(int, 0, bounds=(0, 2**32 - 1), doc="seed of the replicates and extra starts"),
    "min_delta": Param(float, 4.0, bounds=(0.0, None), unit="nat", doc="decision rule: minimum ELPD gain"),
    "se_factor": Param(float, 2.0, bounds=(0.0, None), doc="decision rule: gain / standard error"),
    "closed_fraction": Param(float, 0.5, bounds=(0.0, 1.0), doc="fraction of the gap an explanation must close"),
    "physical_tolerance": Param(float, 2.0, bounds=(0.0, None),
                                doc="decision rule: posterior sd by which a fitted strength may lie outside its "
                                    "physical range (0: the estimate must lie inside)"),
}


def options_from(values: dict) -> Options:
    """:class:`Options` from validated option parameters (the calibration likelihood-ratio threshold of the
    decision rule is the chi^2_1 quantile at ``alpha``)."""
    from scipy.stats import chi2  # the diagnosis's modules load when a diagnosis is set up, not when stages are listed

    from .diagnosis import Options
    from .numerical_error import DEFAULT_VARIANTS

    rule = Rule(values["min_delta"], values["se_factor"], values["closed_fraction"],
                float(chi2.isf(values["alpha"], 1)), values["physical_tolerance"])
    keep = {k: v for k, v in values.items()
            if k not in ("min_delta", "se_factor", "closed_fraction", "physical_tolerance", "numerical_error")}
    variants = DEFAULT_VARIANTS if values.get("numerical_error", True) else ()
    return Options(**(keep | {"variables": tuple(values["variables"]), "rule": rule,
                              "numerical_variants": variants}))


class Diagnose(Stage):
    name = "diagnose"
    # 7: the targeted gap test and the expanded shortlist (issue 20); every unit in UDUNITS form (issue 23)
    # 8: the first step refits every candidate (first_step_refits = "all", issue 20)
    # 9: path_reruns (the verdict along other optimiser paths, off by default; the report records the reruns); the
    #    injection rate as an input-correlation channel (rows only for corefloods with rate steps)
    # 10: with first_round_jacobian = "secant" the declared final model is refitted with forward differences; the
    #     report records every option and the base model's scheme and output step (summary.json "settings")
    # 11: the heldout_predictive and predictive_draws options (the sampled posterior predictive, off by default)
    # 12: heldout_mcse (the sampled predictive's Monte Carlo error) in the report and summary.json
    # 13: heldout_predictive = "sampled" by default (the twin study's rule, docs/gap.md, Scores)
    # 14: heldout_weights (Pareto k and ESS of every sampled held-out score) and the note naming unreliable ones;
    #     the predictive_centre option; each coreflood's measurement model in the report (and a note when assumed)
    # 15: predictive_centre = "newton" by default (its twin rule passed, v10n; docs/gap.md, Scores); the forward
    #     model's dp is the global pressure's (its source digest keys this stage too)
    # 16: dp never interpolated across a rate step, in the data and in the predictions (observations stage 5); the
    #     forward model's record at a slug end is the ending slug's also where the output time is off by rounding;
    #     the data loader's remarks (a CSV's tube rows that look like midpoints) among the notes
    # 17: heldout_weights also give each sampled held-out score's Monte Carlo SE (summary.json)
    version = "17"
    description = "sim-to-real gap diagnosis: where the calibrated model misses, which effect explains it, how far"
    inputs = {"calibrated": DESIGN}
    optional_inputs = frozenset({"calibrated"})
    output = GAP_REPORT
    params = {
        "calibration": Param(list, ["BCF1", "BCF2"],
                             doc="calibration corefloods: bundled names, .nc/.csv paths or study experiments' "
                                 "{name, data, sha256, attrs} mappings"),
        "heldout": Param(list, ["BCF3"], doc="held-out corefloods (empty: leave-one-slug-out scores)"),
        "base": Param(dict, TABLE_3_2_BASE, doc="base model: cells, effects, fixed, parameters, schedules"),
        "catalogue": Param(list, [], doc="candidate effects (empty: every registered effect)"),
        "polish": Param(bool, True, doc="least-squares polish of the best given calibrated parameter set"),
    } | OPTION_PARAMS

    def __init__(self, **params):
        super().__init__(**params)
        self.base_model = BaseModel.from_mapping(self.params["base"])  # every check before any work
        self.catalogue = list(self.params["catalogue"]) or None
        candidates_for(self.catalogue, self.base_model.effects)
        self.options = options_from({k: self.params[k] for k in OPTION_PARAMS})

    @classmethod
    def code_fingerprint(cls) -> str:
        """The stage's source plus the simulator's, so that any physics edit reruns the diagnosis."""
        return f"{super().code_fingerprint()}-{source_digest()[:16]}"

    def _load(self) -> tuple[list[xr.Dataset], list[xr.Dataset]]:
        if getattr(self, "_data", None) is None:
            def load(sources, which):
                out = []
                for source in sources:
                    try:
                        ds = load_observed(source)
                    except (ValueError, OSError) as exc:
                        raise ParameterError(f"stage 'diagnose' parameter {which!r}: {source_label(source)!r}: "
                                             f"{exc}") from None
                    ds.encoding["source"] = source_label(source)  # named in messages about this coreflood's data
                    out.append(ds)
                return out

            self._data = (load(self.params["calibration"], "calibration"), load(self.params["heldout"], "heldout"))
        return self._data

    def fingerprint(self) -> str:
        return canonical_hash(self._load())

    def run(self, ctx: StageContext, calibrated: xr.Dataset | None = None) -> xr.Dataset:
        from .report import report_dataset

        return report_dataset(self.diagnosis(ctx, calibrated))

    def diagnosis(self, ctx: StageContext, calibrated: xr.Dataset | None = None) -> GapDiagnosis:
        """The whole :class:`~spflow.plugins.gap.diagnosis.GapDiagnosis` (``run`` returns its report Dataset)."""
        from .base_calibration import parameter_set_starts
        from .diagnosis import diagnose

        cal, held = self._load()
        sets = None if calibrated is None else parameter_set_starts(self.base_model, calibrated)

        def log(message: str) -> None:
            if ctx.verbose:
                print(f"[{ctx.node}] {message}", file=sys.stderr, flush=True)

        result = diagnose(cal, held, self.base_model, self.catalogue, self.options,
                          parallel=ctx.parallel() if ctx.n_jobs > 1 else None, parameter_sets=sets,
                          polish=self.params["polish"], log=log)
        return result
