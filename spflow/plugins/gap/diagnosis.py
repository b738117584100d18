"""The gap diagnosis: calibrate the base model, localise its misfit, attribute it, quantify the gain (docs/gap.md).

:func:`diagnose` runs the whole procedure on measured corefloods and returns a :class:`GapDiagnosis`;
:mod:`~spflow.plugins.gap.report` turns that into the gap-report Dataset and ``summary.json``, and
:mod:`~spflow.plugins.gap.figures` draws it.

1. **Calibrate** the base model on the calibration experiments (:mod:`~spflow.plugins.gap.base_calibration`),
   measure its own numerical error at the calibrated point (other resolutions and schemes), estimate how much of
   it the calibration residuals hold (:mod:`~spflow.plugins.gap.numerical_scale`) and add that much to the error
   model of every block (:mod:`~spflow.plugins.gap.numerical_error`), then recalibrate (warm start). Fit the
   generic-discrepancy competitor (:mod:`~spflow.plugins.gap.discrepancy`).
2. **Where** — whitened residuals per QoI x slug cell, Ljung-Box whiteness, signature predictive checks, ranked gap
   cells (:mod:`~spflow.plugins.gap.localisation`, :mod:`~spflow.plugins.gap.signatures`), mean-shift change points
   inside slugs (:mod:`~spflow.plugins.gap.change_points`) and residual/input cross-correlations
   (:mod:`~spflow.plugins.gap.input_correlation`); the omnibus test of the calibration gap is
   ``P(chi^2_{n-p} >= chi^2) < alpha`` (the targeted one follows the first refits, step 3).
3. **Which** — projected finite-strength fingerprints of every candidate and their angle matrix
   (:mod:`~spflow.plugins.gap.fingerprints`), refits of "reference + effect" -- every candidate in the first step
   (or a shortlist, extended in screen order while the gap is significant and no refit passes), a shortlist after
   it -- (:mod:`~spflow.plugins.gap.candidates`) scored out of sample (held-out experiments, else leave-one-slug-out;
   :mod:`~spflow.plugins.gap.predictive_scores`, or the sampled posterior predictive of
   :mod:`~spflow.plugins.gap.sampled_predictive` with ``heldout_predictive = "sampled"``; PSIS-LOO on the
   calibration data is reported next to it, :mod:`~spflow.plugins.gap.psis_loo`), the decision rule and greedy addition of further effects
   (:mod:`~spflow.plugins.gap.verdict`; the calibration gap is significant on the omnibus or the targeted test).
4. **How far** — gap closed, RMSE ratios, interval coverage and parameter shifts of the final model against the
   base (:mod:`~spflow.plugins.gap.quantification`).
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass, field, replace

import numpy as np
from scipy.stats import chi2

from spflow.core.errors import ParameterError
from spflow.plugins.forward.parameters import resolve_params

from .base_calibration import calibrate_base
from .base_model import BaseModel
from .candidates import FIRST_STEP_REFITS, fingerprint_columns, refit, screen_order, shortlist
from .cost import Cost, CostLedger
from .catalogue import MAX_EFFECTS, CandidateEffect, candidates_for
from .discrepancy import Discrepancy, fit_discrepancy
from .dispersion_note import dispersion_note
from .change_points import ChangePoint, change_points
from .fingerprints import NuisanceProjector, ScreenResult, screen
from .input_correlation import InputCorrelation, input_correlations
from .layout import Layout, make_layout
from .least_squares import FIRST_ROUND_JACOBIANS, Fit, WhitenedProblem, fit
from .localisation import Cell, cells, gap_cells, ljung_box
from .numerical_error import DEFAULT_VARIANTS, NumericalSpread, Numerics, inflate, numerical_spread
from .numerical_scale import NumericalScale, estimate_scale
from .path_stability import MAX_RERUNS, PathRerun, rerun_paths
from .observed import MEASURABLE, Experiment, load_experiments, measurement_note, rate_step_note
from .prediction import Predictor
from .predictive_scores import Predictive, compare, leave_one_slug_out, predictive
from .psis_loo import compare_loo, psis_loo
from .sampled_predictive import (HELDOUT_PREDICTIVES, PROPOSAL_CENTRES, is_unreliable, sampled_predictive,
                                 unreliable_weights_note)
from .quantification import gap_closed, parameter_covariance, predictive_std, raw_jacobian
from .signatures import predictive_pvalues, signatures
from .subsets import SearchResult, SubsetFit, best_subset, subset_key
from .verdict import CandidateScore, Rule, ambiguity_set, passes, targeted_pvalue, verdict

__all__ = ["Options", "GapDiagnosis", "ModelView", "Step", "diagnose"]


@dataclass(frozen=True)
class Options:
    """Settings of a diagnosis (the ``diagnose`` stage's parameters)."""

    variables: tuple[str, ...] = ("dp", "oil_cut")
    pv_step: float = 0.1
    alpha: float = 0.01
    shortlist: int = 3
    max_effects: int = 2
    max_nfev: int = 30
    starts: int = 1
    nuisance_scale: float = 0.5
    cos_threshold: float = 0.9
    rule: Rule = field(default_factory=Rule)
    replicates: int = 200
    interval: float = 0.9
    seed: int = 0
    diff_step: float = 0.01
    loso_nfev: int = 8
    max_lag: float = 1.5
    min_segment: int = 3
    null_draws: int = 20000
    loo_draws: int = 2000
    numerical_variants: tuple[Numerics, ...] = DEFAULT_VARIANTS
    numerical_window: int = 3
    #: cap of the estimated scale of the numerical-error term (:mod:`~spflow.plugins.gap.numerical_scale`)
    numerical_scale_max: float = 1.0
    discrepancy_degree: int = 2
    subset_pool: int = 4
    #: the first step's refits: ``"all"`` (every candidate, in screen order) or ``"shortlist"`` (the screen's
    #: shortlist, extended by ``expand_shortlist``); the linear screen misorders effects whose fingerprints the
    #: recalibration bends (the polymer-viscosity trio), so a shortlist can leave the truth unfitted (docs/gap.md)
    first_step_refits: str = "all"
    #: with ``first_step_refits = "shortlist"``: refit further candidates in screen order while the gap is
    #: significant and no refit passes
    expand_shortlist: bool = True
    #: exact cost reductions on (same results, fewer forward runs and less CPU; ``False``: the behaviour before,
    #: for benchmarks)
    economy: bool = True
    #: Jacobians of the first, budgeted round of every multi-start fit (candidate refits, joint subset refits, a
    #: multi-start base calibration): ``"difference"`` (a forward difference at every accepted step) or ``"secant"``
    #: (Broyden updates from one forward difference per start: 0.4-0.55 of the forward runs, and a declared final
    #: model refitted with forward differences from where it stopped; it changes results -- verdicts and ambiguity
    #: sets of single twins, the final fit of the bundled data -- so it is opt-in; least_squares.py, docs/gap.md,
    #: Cost)
    first_round_jacobian: str = "difference"
    #: reruns of the whole diagnosis along other optimiser paths (the difference step scaled by 1.1, 0.9, ...), to
    #: show whether the verdict holds (:mod:`~spflow.plugins.gap.path_stability`); 0: not checked
    path_reruns: int = 0
    #: the held-out coreflood's predictive distribution under each calibrated model: ``"laplace"`` (linearised at
    #: the optimum) or ``"sampled"`` (the posterior predictive by importance sampling from ``predictive_draws``
    #: draws of the Laplace posterior: integrates over the flat valleys the linearisation misjudges; about
    #: 2 x ``predictive_draws`` forward runs per scored model; the default since the twin study judged it by the
    #: rule fixed before it ran, docs/gap.md, Scores). Without held-out corefloods the leave-one-slug-out scores
    #: are linearised whatever this says (the run says so and the report's notes record it).
    heldout_predictive: str = "sampled"
    predictive_draws: int = 100
    #: the sampled predictive's proposal mean: the calibrated optimum, or the minimiser of the Gauss-Newton model
    #: of the calibration chi2 there (``"newton"``: corrects an optimum short of convergence or pressed against the
    #: box; sampled_predictive.proposal_mean, docs/gap.md, Scores; the default since its twin rule passed, v10n)
    predictive_centre: str = "newton"

    def as_dict(self) -> dict:
        """Every option as JSON values (the rule and the numerical variants as nested dicts)."""
        return asdict(self)

    def line(self) -> str:
        """The options on one line, defaults included (printed and recorded with every diagnosis)."""
        return "diagnosis options: " + ", ".join(f"{k} = {v!r}" for k, v in self.as_dict().items())


@dataclass
class Step:
    """One round of screening and refitting on top of a model (``reference``), scored against the last accepted
    model (``scored_against``)."""

    reference: str
    scored_against: str
    screen: ScreenResult
    shortlisted: list[str]
    fits: dict[str, Fit]
    scores: dict[str, CandidateScore]
    out_of_sample: dict[str, Predictive]
    loo: dict[str, tuple[float, float, float]] = field(default_factory=dict)


@dataclass
class ModelView:
    """A calibrated model seen on every measured point (``layout_all``): predictions, residuals, intervals."""

    fit: Fit
    prediction: np.ndarray
    residual: np.ndarray
    whitened: np.ndarray
    std: np.ndarray
    cells: list[Cell]
    ljung_box: dict[tuple[str, str], tuple[float, float, int]]
    signatures: dict[str, dict[str, tuple[float, float]]]
    predicted_signatures: dict[str, dict[str, float]]
    change_points: list[ChangePoint]
    input_correlations: list[InputCorrelation]


@dataclass
class GapDiagnosis:
    """Everything a gap report shows (see :mod:`~spflow.plugins.gap.report`)."""

    options: Options
    base: BaseModel
    calibration: list[Experiment]
    heldout: list[Experiment]
    candidates: list[CandidateEffect]
    layout_fit: Layout
    layout_score: Layout
    layout_all: Layout
    score_kind: str
    base_fit: Fit
    chi2_pvalue: float
    gap_significant: bool
    steps: list[Step]
    accepted: list[list[str]]
    verdict: str
    ambiguity: list[str]
    final_fit: Fit
    final_label: str
    out_of_sample_base: Predictive
    out_of_sample_final: Predictive
    base_view: ModelView
    final_view: ModelView
    gap_cells: list[Cell]
    wall_time_s: float
    forward_runs: int
    chi2_measurement_only: float = float("nan")
    numerical: NumericalSpread | None = None
    numerical_scale: NumericalScale | None = None
    discrepancy: Discrepancy | None = None
    out_of_sample_discrepancy: Predictive | None = None
    search: SearchResult | None = None
    search_pool: list[str] = field(default_factory=list)
    search_runs: int = 0
    tried: dict[str, float] = field(default_factory=dict)
    notes: list[str] = field(default_factory=list)
    cost: dict[str, Cost] = field(default_factory=dict)
    #: the targeted test of the calibration gap (verdict.targeted_pvalue; NaN before any refit)
    targeted_pvalue: float = float("nan")
    #: with an ``unattributed`` verdict, the physical candidates of the first step that close half the calibration
    #: gap without passing out of sample (best held-out score first; verdict.verdict's ``closers``), else empty
    closers: list[str] = field(default_factory=list)
    #: the reruns along other optimiser paths (``Options.path_reruns``), empty when not checked
    path_reruns: list[PathRerun] = field(default_factory=list)
    #: model label -> (Pareto k, effective sample size, Monte Carlo SE in nats) of every sampled held-out predictive
    #: the diagnosis scored (``heldout_predictive = "sampled"``; the discrepancy competitor shares the base's
    #: draws); those with ``k > RELIABLE_PARETO_K`` are named in ``notes``
    heldout_weights: dict[str, tuple[float, float, float]] = field(default_factory=dict)

    @property
    def dof(self) -> int:
        return self.layout_fit.size - len(self.base.parameters)


def _series(layout: Layout, values: np.ndarray, exp: Experiment) -> dict[str, np.ndarray]:
    """Per-variable grid series of ``exp`` from a layout vector (NaN off the measured points)."""
    out = {}
    for b, s in zip(layout.blocks, layout.slices()):
        if b.experiment == exp.name:
            series = np.full(exp.pv.size, np.nan)
            series[b.index] = values[s]
            out[b.variable] = series
    return out


def _view(fitted, predictor, layout, experiments, options, rng) -> ModelView:
    y, jac = raw_jacobian(predictor, layout, fitted, options.diff_step)
    cov = parameter_covariance(fitted.jacobian, options.nuisance_scale)
    std = predictive_std(layout, jac, cov)
    obs = layout.observed()
    e = y - obs
    w = layout.whiten(e)
    slug_names = {x.name: [s.name for s in x.schedule.slugs] for x in experiments}
    lb = {(b.variable, b.experiment): ljung_box(w[s]) for b, s in zip(layout.blocks, layout.slices())}
    # replicated data for the signature checks: linearised parameter draws plus measurement errors
    dz = rng.multivariate_normal(np.zeros(cov.shape[0]), cov, size=options.replicates, method="eigh")
    reps = y + dz @ jac.T
    for b, s in zip(layout.blocks, layout.slices()):
        reps[:, s] += b.noise.draw(rng, options.replicates)
    sigs, pred_sigs = {}, {}
    for exp in experiments:
        sigs[exp.name] = predictive_pvalues(exp, _series(layout, obs, exp),
                                            [_series(layout, r, exp) for r in reps])
        pred_sigs[exp.name] = signatures(exp, _series(layout, y, exp))
    cps = change_points(layout, w, e, slug_names, options.alpha, options.min_segment, options.null_draws,
                        options.seed)
    params, _ = predictor.model(fitted.u)
    qinj = {x.name: resolve_params({**x.core, **params})["QINJ"] for x in experiments}  # as the runs see it
    xcorr = input_correlations(layout, w, experiments, qinj, options.alpha, options.max_lag, options.pv_step,
                               options.null_draws, options.seed, reuse=options.economy)
    return ModelView(fitted, y, e, w, std, cells(layout, w, e, slug_names), lb, sigs, pred_sigs, cps, xcorr)


def _label(fitted: Fit) -> str:
    return "+".join(["base"] + [c.name for c in fitted.candidates])


def _slug_names(experiments: Sequence[Experiment]) -> dict[str, list[str]]:
    return {e.name: [slug.name for slug in e.schedule.slugs] for e in experiments}


def _strength_sd(f: Fit, tau: float) -> dict[str, float]:
    """Linearised posterior sd of every freed strength's unit-box coordinate."""
    cov = parameter_covariance(f.jacobian, tau)
    return {c.name: float(np.sqrt(cov[f.n_params + j, f.n_params + j])) for j, c in enumerate(f.candidates)}


def _strength_z(f: Fit, tau: float) -> dict[str, float]:
    """z of every freed strength against its base strength (linearised posterior sd in the unit box)."""
    sd = _strength_sd(f, tau)
    return {c.name: float((f.z[f.n_params + j] - c.unit(c.base)) / sd[c.name]) for j, c in enumerate(f.candidates)}


def _physical(f: Fit, tau: float, rule: Rule) -> dict[str, bool]:
    """Whether every freed strength is consistent with its physical range: inside it or within
    ``rule.physical_tolerance`` posterior sd of it (verdict.py)."""
    sd = _strength_sd(f, tau)
    return {c.name: c.is_physical(f.strengths[c.name], rule.physical_tolerance * sd[c.name]) for c in f.candidates}


def _recalibrate(predictor: Predictor, layout: Layout, start: Fit, options: Options, polish: bool) -> Fit:
    """The base model on a re-weighted ``layout`` from ``start`` (a warm refit, or only the residuals and
    Jacobian there when the given parameter set is not to be polished)."""
    if polish:  # (keeps the original start: candidate refits restart from it, not from the re-weighted optimum)
        return replace(fit(predictor, layout, [start.z], max_nfev=options.max_nfev, diff_step=options.diff_step),
                       start=start.start)
    problem = WhitenedProblem(predictor, layout, (), start.n_params, options.diff_step)
    return Fit(start.z, (), start.n_params, problem.fun(start.z), problem.jac(start.z), 0, start.message,
               start.start)


def diagnose(calibration: Sequence, heldout: Sequence, base: BaseModel, catalogue: Sequence[str] | None = None,
             options: Options | None = None, *, parallel=None, parameter_sets: np.ndarray | None = None,
             polish: bool = True, log: Callable[[str], None] | None = None) -> GapDiagnosis:
    """Diagnose the sim-to-real gap of ``base`` on corefloods ``calibration`` (names, paths or Datasets), scoring
    candidates on ``heldout`` (or leave-one-slug-out when empty). See the module docstring."""
    options = options or Options()
    say = log or (lambda msg: None)
    notes: list[str] = []
    start = time.perf_counter()
    if not calibration:
        raise ParameterError("a diagnosis needs at least one calibration coreflood")
    if not 1 <= options.max_effects <= MAX_EFFECTS:
        raise ParameterError(f"max_effects = {options.max_effects!r} is out of range; allowed 1..{MAX_EFFECTS} "
                             "(effects the search may add)")
    if not 0.0 <= options.numerical_scale_max <= 10.0:
        raise ParameterError(f"numerical_scale_max = {options.numerical_scale_max!r} is out of range; allowed "
                             "[0, 10] (the cap of the numerical-error scale)")
    if options.first_step_refits not in FIRST_STEP_REFITS:
        raise ParameterError(f"first_step_refits = {options.first_step_refits!r} is not allowed; allowed "
                             f"{list(FIRST_STEP_REFITS)}")
    if not 0 <= options.path_reruns <= MAX_RERUNS:
        raise ParameterError(f"path_reruns = {options.path_reruns!r} is out of range; allowed 0..{MAX_RERUNS} "
                             "(reruns along other optimiser paths)")
    if options.first_round_jacobian not in FIRST_ROUND_JACOBIANS:
        raise ParameterError(f"first_round_jacobian = {options.first_round_jacobian!r} is not allowed; allowed "
                             f"{list(FIRST_ROUND_JACOBIANS)}")
    if options.heldout_predictive not in HELDOUT_PREDICTIVES:
        raise ParameterError(f"heldout_predictive = {options.heldout_predictive!r} is not allowed; allowed "
                             f"{list(HELDOUT_PREDICTIVES)}")
    if options.predictive_centre not in PROPOSAL_CENTRES:
        raise ParameterError(f"predictive_centre = {options.predictive_centre!r} is not allowed; allowed "
                             f"{list(PROPOSAL_CENTRES)}")
    if not 20 <= options.predictive_draws <= 10000:
        raise ParameterError(f"predictive_draws = {options.predictive_draws!r} is out of range; allowed 20..10000 "
                             "(draws of the sampled held-out predictive)")
    cal = load_experiments(calibration, options.pv_step, base.schedules)
    held = load_experiments(heldout, options.pv_step, base.schedules)
    clash = sorted({e.name for e in cal} & {e.name for e in held})
    if clash:
        raise ParameterError(f"experiments {clash} are both calibration and held-out data")
    assumed = measurement_note(cal + held)
    if assumed:
        notes.append(assumed)
    notes.extend(note for e in cal + held for note in e.data_notes)
    stepped = rate_step_note(cal + held)
    if stepped:
        notes.append(stepped)
    candidates = candidates_for(catalogue, base.effects)
    predictor = Predictor(base, cal + held, parallel)
    ledger = CostLedger(predictor)
    layout_fit = make_layout(cal, options.variables)
    missing = sorted(set(options.variables) - {b.variable for b in layout_fit.blocks})
    if missing:
        raise ParameterError(f"variables {missing} are not measured in the calibration data "
                             f"({', '.join(e.name for e in cal)})")
    if layout_fit.size <= len(base.parameters):
        raise ParameterError(f"{layout_fit.size} calibration points cannot calibrate {len(base.parameters)} "
                             "parameters")
    layout_held = make_layout(held, options.variables)
    layout_all = make_layout(cal + held, report_only=[v for v in MEASURABLE if v not in options.variables],
                             dropped=notes)
    kind = "heldout" if layout_held.size else "leave_one_slug_out"
    if not layout_held.size and options.heldout_predictive == "sampled":
        notes.append("no held-out coreflood: the candidates are scored by leave-one-slug-out with the linearised "
                     "predictive (heldout_predictive = 'sampled' applies to held-out corefloods only)")
    say(options.line())
    for note in notes:
        say(note)
    slug_names = _slug_names(cal + held)

    ledger.enter("base calibration")
    say(f"calibrating the base model on {', '.join(e.name for e in cal)} ({layout_fit.size} points)")
    base_fit = calibrate_base(predictor, layout_fit, starts=options.starts, seed=options.seed,
                              max_nfev=options.max_nfev, diff_step=options.diff_step,
                              parameter_sets=parameter_sets, polish=polish, economy=options.economy,
                              first_round=options.first_round_jacobian)
    chi2_measurement = base_fit.chi2
    numerical, scale = None, None
    if options.numerical_variants:
        ledger.enter("numerical error")
        numerical = numerical_spread(predictor, base_fit, options.numerical_variants, options.numerical_window)
        ledger.add_runs("numerical error", numerical.runs, numerical.run_cpu)
        # the size of the term: from the base fit's residuals and Jacobian (its forward runs are memoised)
        y_fit, jac_fit = raw_jacobian(predictor, layout_fit, base_fit, options.diff_step)
        scale = estimate_scale(layout_fit, numerical.series, y_fit - layout_fit.observed(), jac_fit,
                               options.nuisance_scale, options.numerical_scale_max)
        layout_fit, layout_held, layout_all = (inflate(x, numerical.series, scale.estimate)
                                               for x in (layout_fit, layout_held, layout_all))
        say(f"numerical error of the base model ({'; '.join(numerical.variants)}), scaled by {scale.label()}, "
            f"added to the error model: chi2 {chi2_measurement:.1f} with measurement error only")
        if scale.estimate > 0.0:  # (at s = 0 the error model is the measurement model: the fit stands)
            ledger.enter("base calibration")
            base_fit = _recalibrate(predictor, layout_fit, base_fit, options, polish or parameter_sets is None)
    layout_score = layout_held if layout_held.size else layout_fit
    dof = layout_fit.size - len(base.parameters)
    pvalue = float(chi2.sf(base_fit.chi2, dof))
    say(f"base chi2 = {base_fit.chi2:.1f} on {dof} dof (p = {pvalue:.3g}); {predictor.runs} forward runs")

    heldout_weights: dict[str, tuple[float, float, float]] = {}

    def held_out(f: Fit, shift: np.ndarray | None = None) -> Predictive:
        if options.heldout_predictive == "laplace":
            return predictive(predictor, layout_held, f, options.nuisance_scale, options.diff_step, shift=shift)
        problems = [WhitenedProblem(predictor, layout, f.candidates, len(base.parameters), options.diff_step)
                    for layout in (layout_fit, layout_held)]
        w = sampled_predictive(problems[0].residuals, problems[1].residuals, f, tau=options.nuisance_scale,
                               draws=options.predictive_draws, seed=options.seed, centre=options.predictive_centre,
                               shift=None if shift is None else layout_held.whiten(shift))
        model = _label(f) + ("" if shift is None else " (discrepancy competitor)")
        say(f"sampled held-out predictive of {model}: effective sample size {w.ess:.1f} of "
            f"{options.predictive_draws} draws, Pareto k {w.pareto_k:.2f}, Monte Carlo SE {w.mcse:.2f} nats")
        if shift is None:  # (the competitor shifts the base's draws: same weights, same k and ESS)
            heldout_weights[model] = (w.pareto_k, w.ess, w.mcse)
        return w

    def out_of_sample(f: Fit) -> Predictive:
        left = ledger.enter("scores")
        if layout_held.size:
            w = held_out(f)
        else:
            w = leave_one_slug_out(predictor, layout_fit, f, tau=options.nuisance_scale, max_nfev=options.loso_nfev,
                                   diff_step=options.diff_step)
        ledger.enter(left)
        return w

    ledger.enter("scores")
    w_base = out_of_sample(base_fit)
    # the generic-discrepancy competitor: fitted on the calibration data, its transferable part predicts held-out
    y_base = layout_fit.vector(predictor.predict([base_fit.point], layout_fit.experiments, layout_fit.variables)[0])
    disc = fit_discrepancy(layout_fit, y_base - layout_fit.observed(), slug_names, options.discrepancy_degree)
    w_disc = None
    if layout_held.size:
        w_disc = held_out(base_fit, disc.shift(layout_held, slug_names))
        say(f"discrepancy competitor: calibration chi2 {disc.chi2:.1f} ({disc.n_terms} terms), held-out "
            f"dELPD over the base {compare(w_disc, w_base)[0]:.1f}")
    competitors = [w_disc] if w_disc is not None else []

    def score(c: CandidateEffect, f: Fit, w: Predictive, w_ref: Predictive, reference_chi2: float,
              physical: bool) -> CandidateScore:
        delta, se, se_pointwise = compare(w, w_ref)
        cd, cse = compare(w, w_disc)[:2] if w_disc is not None else (float("nan"), float("nan"))
        white = w.whitened[np.isfinite(w.whitened)]
        dispersion = max(1.0, float(np.mean(white**2))) if white.size else 1.0
        return CandidateScore(c.name, delta, se, se_pointwise, f.strengths[c.name],
                              _strength_z(f, options.nuisance_scale)[c.name], physical,
                              gap_closed(base_fit.chi2, f.chi2, dof), reference_chi2 - f.chi2, w.gradient, cd, cse,
                              dispersion)

    # ``reference``: the last accepted model (what a candidate must beat out of sample); ``fitting``: the model the
    # next candidates are added to -- the reference, or a provisional first effect when no single effect passes
    reference, w_ref, fitting, provisional = base_fit, w_base, base_fit, None
    remaining = list(candidates)
    steps: list[Step] = []
    accepted: list[list[str]] = []
    # the calibration gap: the omnibus test now, the targeted test once the first refits are in (verdict.py)
    significant, targeted = pvalue < options.alpha, float("nan")
    while remaining and len(fitting.candidates) < options.max_effects:
        ledger.enter("screening")
        cols = fingerprint_columns(predictor, layout_fit, fitting, remaining)
        result = screen([c.name for c in remaining], [c.levels for c in remaining], cols, -fitting.residual,
                        NuisanceProjector(fitting.jacobian, options.nuisance_scale))
        chosen = (screen_order(result) if not steps and options.first_step_refits == "all"
                  else shortlist(result, options.shortlist, options.cos_threshold))
        step = Step(_label(fitting), _label(reference), result, [remaining[i].name for i in chosen], {}, {}, {})
        loo_ref = psis_loo(reference, options.nuisance_scale, options.loo_draws, options.seed)
        ledger.enter("refits")

        def add_refit(i: int) -> None:
            c = remaining[i]
            say(f"refitting {_label(fitting)}+{c.name} (screen z = {result.best_z()[i]:.2f})")
            f = refit(predictor, layout_fit, fitting, c, base_fit.start[: base_fit.n_params],
                      max_nfev=options.max_nfev, diff_step=options.diff_step, economy=options.economy,
                      first_round=options.first_round_jacobian)
            w = out_of_sample(f)
            consistent = _physical(f, options.nuisance_scale, options.rule)
            physical = all(consistent[x.name] for x in f.candidates if x.name not in
                           {n for names in accepted for n in names})
            step.fits[c.name], step.out_of_sample[c.name] = f, w
            loo = psis_loo(f, options.nuisance_scale, options.loo_draws, options.seed)
            k = loo.pareto_k[np.isfinite(loo.pareto_k)]
            step.loo[c.name] = (*compare_loo(loo, loo_ref), float(k.max()) if k.size else float("nan"))
            step.scores[c.name] = score(c, f, w, w_ref, fitting.chi2, physical)

        for i in chosen:
            add_refit(i)
        if not steps:
            # the screen is linear: an effect the nuisance projector calls absorbed can still leave a gap that
            # the nonlinear recalibration does not close (permeability reduction against the polymer viscosity
            # coefficients). While the gap is significant and no refit passes, refit the next candidates in
            # screen order, ``shortlist`` at a time, until one passes or the catalogue is exhausted.
            order = [i for i in screen_order(result) if i not in chosen]

            def gap_test() -> tuple[float, bool]:  # (targeted p, gap significant on either test)
                p = targeted_pvalue([x.chi2_drop for x in step.scores.values()], len(candidates))
                return p, significant or p < options.alpha

            targeted, found = gap_test()
            while (options.expand_shortlist and order and found
                   and not any(passes(x, options.rule) for x in step.scores.values())):
                batch, order = order[: options.shortlist], order[options.shortlist:]
                say(f"no refit passes: refitting the next candidates in screen order "
                    f"({', '.join(remaining[i].name for i in batch)})")
                for i in batch:
                    add_refit(i)
                    step.shortlisted.append(remaining[i].name)
                targeted, found = gap_test()
            if found and not significant:
                say(f"calibration gap significant on the targeted test only (p = {targeted:.3g}; omnibus p = "
                    f"{pvalue:.3g})")
            significant = found
        steps.append(step)
        # nothing is accepted without a significant calibration gap (verdict.py: gains only out of sample)
        chosen_set = ambiguity_set(list(step.scores.values()), options.rule) if significant else []
        if chosen_set:
            accepted += ([[provisional]] if provisional else []) + [[s.name for s in chosen_set]]
            best = chosen_set[0].name
            reference = fitting = step.fits[best]
            w_ref, provisional = step.out_of_sample[best], None
            remaining = [c for c in remaining if c.name != best]
            if chi2.sf(reference.chi2, dof - len(reference.candidates)) >= options.alpha:
                break  # no significant calibration gap left
            continue
        closers = [x for x in step.scores.values() if x.physical and x.chi2_drop > 0.0]
        if provisional is not None or fitting is not base_fit or not significant or not closers:
            break  # (refits without a calibration gap are reported, not used)
        # no single effect passes out of sample although the calibration gap is significant: two mechanisms may
        # compensate each other, so add a second effect to the one closing most of the calibration gap and score
        # the pair against the reference (the provisional effect is accepted only together with its partner)
        provisional = max(closers, key=lambda x: x.chi2_drop).name
        fitting = step.fits[provisional]
        remaining = [c for c in remaining if c.name != provisional]
    accepted = [[n for n in names if n == names[0] or all(n not in later for later in accepted[k + 1:])]
                for k, names in enumerate(accepted)]  # an effect accepted later is no longer ambiguous

    # joint search over the shortlisted pool when the greedy path found fewer than two effects and left a
    # significant calibration gap (subsets.py; the failure mode of compensating effects -- with two or more effects
    # found greedily the search is skipped: its joint refits would cost several times the whole diagnosis)
    search, pool, search_runs = None, [], 0
    gap_left = significant if reference is base_fit else \
        chi2.sf(reference.chi2, dof - len(reference.candidates)) < options.alpha
    if significant and gap_left and len(accepted) < 2 and options.max_effects >= 2 and steps:
        first = steps[0]
        ranked = sorted(first.scores, key=lambda n: -first.scores[n].delta_elpd)
        z = dict(zip(first.screen.names, first.screen.best_z()))
        ranked += sorted((n for n in z if n not in ranked), key=lambda n: -abs(z[n]))
        pool = list(dict.fromkeys([n for names in accepted for n in names[:1]] + ranked))[: options.subset_pool]
        by_name = {c.name: c for c in candidates}
        fits: dict[tuple[str, ...], Fit] = {(): base_fit}
        fits.update({(n,): f for n, f in first.fits.items()})
        outs: dict[tuple[str, ...], Predictive] = {(): w_base}
        outs.update({(n,): w for n, w in first.out_of_sample.items()})
        before = predictor.runs
        ledger.enter("subsets")

        def evaluate(names: tuple[str, ...]) -> SubsetFit:
            if names not in fits:
                effects = tuple(by_name[n] for n in names)
                single = [fits[(n,)].z[-1] if (n,) in fits else by_name[n].unit(by_name[n].levels[0]) for n in names]
                starts = [np.concatenate((base_fit.z, single))]
                for k, n in enumerate(names):  # the best sub-fit, with the missing effect at its single strength
                    sub = tuple(m for m in names if m != n)
                    if sub in fits and len(sub) > 1:
                        starts.append(np.insert(fits[sub].z, base_fit.n_params + k, single[k]))
                        break
                say(f"joint refit base+{'+'.join(names)}")
                fits[names] = fit(predictor, layout_fit, starts, effects, max_nfev=options.max_nfev,
                                  diff_step=options.diff_step, economy=options.economy,
                                  first_round=options.first_round_jacobian)
            f = fits[names]
            if names not in outs:
                outs[names] = out_of_sample(f)
            return SubsetFit(names, f.chi2, f.strengths, _strength_z(f, options.nuisance_scale),
                             _physical(f, options.nuisance_scale, options.rule), outs[names])

        search = best_subset(pool, evaluate, options.rule, options.max_effects, competitors)
        search_runs = predictor.runs - before
        say(f"subset search over {pool}: {len(search.fits)} subsets, admissible {search.admissible}, chosen "
            f"{list(search.chosen)} ({search_runs} forward runs)")
        current = subset_key(c.name for c in reference.candidates)
        if search.chosen and (not accepted or outs[search.chosen].total > outs.get(current, w_ref).total):
            order = sorted(search.chosen, key=lambda n: -(first.scores[n].delta_elpd if n in first.scores
                                                          else -np.inf))
            partners = accepted[0][1:] if accepted and accepted[0][0] == order[0] else []
            accepted = [[order[0]] + [p for p in partners if p not in order]] + [[n] for n in order[1:]]
            reference = fits[search.chosen]
            w_ref = outs[search.chosen]

    final_closed = gap_closed(base_fit.chi2, reference.chi2, dof)

    def closes(s: CandidateScore) -> bool:  # (a gap only the targeted test finds has no fraction to close)
        if np.isfinite(s.gap_closed):
            return s.gap_closed >= options.rule.closed_fraction
        return targeted_pvalue([s.chi2_drop], len(candidates)) < options.alpha

    closers = [] if accepted else [s.name for s in sorted(steps[0].scores.values(), key=lambda s: -s.delta_elpd)
                                   if s.physical and closes(s)]
    decided, ambiguity = verdict(accepted, significant, final_closed, closers, options.rule)
    declared = decided in ("effect", "ambiguous")
    if not declared:
        reference, w_ref = base_fit, w_base  # nothing declared: the final model is the base
    elif options.first_round_jacobian == "secant":
        # the secant first round leaves the continued start less converged (docs/gap.md, Cost): the declared model
        # gets one more forward-difference fit from where it stopped. It can only lower chi2, i.e. close more of
        # the gap, and a declared verdict stays declared when the closed fraction grows: verdict and set stand
        ledger.enter("final fit")
        reference = fit(predictor, layout_fit, [reference.z], reference.candidates, max_nfev=options.max_nfev,
                        diff_step=options.diff_step, economy=options.economy)
        w_ref = out_of_sample(reference)
        say(f"final model refitted with forward differences: chi2 {reference.chi2:.1f}")
    # refitted candidates outside the final model, at their single-effect strengths ("tried, not declared")
    tried = {name: sc.strength for step in reversed(steps) for name, sc in step.scores.items()
             if name not in reference.strengths}
    say(f"verdict: {decided} {ambiguity}")
    unreliable = {m: kw for m, kw in heldout_weights.items() if is_unreliable(kw[0])}
    if unreliable:
        notes.append(unreliable_weights_note(unreliable, options.predictive_draws))
        say(notes[-1])
    if "dispersion" in {*ambiguity, *reference.strengths}:  # named: declared, or in the set (then refitted: tried)
        strength = reference.strengths.get("dispersion", tried.get("dispersion"))
        notes.append(dispersion_note(strength, resolve_params(predictor.model(reference.u)[0])["ALPHAL1"]))
        say(notes[-1])

    rng = np.random.default_rng(options.seed)
    everything = cal + held
    ledger.enter("views")
    base_view = _view(base_fit, predictor, layout_all, everything, options, rng)
    final_view = base_view if reference is base_fit else _view(reference, predictor, layout_all, everything, options,
                                                                rng)
    runs = predictor.runs + (numerical.runs if numerical is not None else 0)

    def rerun(step: float) -> tuple[str, list[str], dict[str, float], int]:
        say(f"rerunning the diagnosis along another optimiser path: difference step {step:g}")
        g = diagnose(calibration, heldout, base, catalogue, replace(options, diff_step=step, path_reruns=0),
                     parallel=parallel, parameter_sets=parameter_sets, polish=polish,
                     log=lambda msg: say(f"[difference step {step:g}] {msg}"))
        return g.verdict, g.ambiguity, g.final_fit.strengths, g.forward_runs

    reruns = rerun_paths(rerun, options.diff_step, options.path_reruns, decided, ambiguity, reference.strengths)
    for r in reruns:
        say(f"difference step {r.diff_step:g}: {r.verdict} {r.ambiguity_set} -- "
            f"{'agrees' if r.agrees else 'DIFFERS from the main run'}")
    return GapDiagnosis(options, base, cal, held, candidates, layout_fit, layout_score, layout_all, kind, base_fit,
                        pvalue, significant, steps, accepted, decided, ambiguity, reference,
                        _label(reference), w_base, w_ref, base_view, final_view,
                        gap_cells([c for c in base_view.cells if c.variable in options.variables], options.alpha),
                        time.perf_counter() - start, runs, chi2_measurement, numerical, scale, disc, w_disc, search,
                        pool, search_runs, tried, notes, ledger.table(), targeted,
                        closers if decided == "unattributed" else [], reruns, heldout_weights)
