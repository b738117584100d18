"""The next experiment: the coreflood that best separates competing hypotheses, with its predicted power.

When a diagnosis ends ambiguous (several calibrated models -- *hypotheses* -- explain the data about equally
well) or an effect is weakly identified, :func:`rank_designs` ranks candidate corefloods
(:func:`~spflow.plugins.gap.design_space.design_space`) by how well each would tell the hypotheses apart, in the
spirit of Box & Hill (1967): choose the experiment where the candidate models' predictions differ most relative to
their predictive spread (docs/next_experiment.md).

**Predictive distributions.** Each hypothesis ``m`` is a calibrated model (a :class:`~spflow.plugins.gap.
least_squares.Fit`: unit-box parameters and effect strengths) with a linearised parameter covariance ``C_m``
(:func:`~spflow.plugins.gap.quantification.parameter_covariance`). On a design it is run through the reference
coreflood's measurement chain (:class:`~spflow.plugins.gap.prediction.Predictor`: the same core, transducer,
dead volume and fraction collector), giving the mean ``mu_m`` and the Jacobian ``J_m`` of the predictions. When
hypothesis ``a`` is true, the data's error model (:mod:`~spflow.plugins.gap.error_model`, the AR(1)/random-walk
model of the diagnosis's likelihood, scaled from the data, i.e. from ``mu_a``) has whitening ``W_a``; in whitened
coordinates ``w = W_a (y - mu_a)`` the data are ``N(0, S_a)`` and hypothesis ``m`` predicts ``N(d_m, S_m)`` with

    d_m = W_a (mu_m - mu_a),    S_m = I + (W_a J_m) C_m (W_a J_m)'

-- exactly the held-out predictive density the diagnosis scores models with
(:mod:`~spflow.plugins.gap.predictive_scores`). With ``parameter_draws > 0`` the parameter term is instead the
second moment of the whitened predictions at that many draws from ``N(z_m, C_m)`` about the fit's prediction: a
design whose discrimination rests on a regime change inside the parameter uncertainty (e.g. a surfactant phase
transition that one hypothesis crosses) then gets the spread the linearisation misses.

**Expected discrimination.** The log predictive ratio ``L_ab = log p_a(y) - log p_b(y)`` (the held-out dELPD of
``a`` over ``b``) under ``a`` has mean and variance (standard Gaussian identities; ``M = S_b^-1 - S_a^-1``)

    E[L_ab]   = KL(a || b) = 1/2 [tr(S_b^-1 S_a) + d_b' S_b^-1 d_b - n + ln det S_b - ln det S_a]
    Var[L_ab] = 1/2 tr((M S_a)^2) + d_b' S_b^-1 S_a S_b^-1 d_b.

The decision rule prefers ``a`` over ``b`` when ``L_ab`` exceeds ``min_delta`` and ``se_factor`` times its
measurement SE ``||S_a^-1 (w - d_a) - S_b^-1 (w - d_b)||`` (:mod:`~spflow.plugins.gap.verdict`,
:mod:`~spflow.plugins.gap.predictive_scores`). Because ``L_ab`` is a quadratic form in the data whenever the two
predictive covariances differ (its distribution is skewed: the normal approximation put the power of a nested
pair at 0.92 where simulation gives 0.99), the **predicted power** ``P(a preferred over b | a)`` and the
**decision accuracy** ``P(a preferred over every alternative | a)`` are simulated: ``draws`` data sets
``w ~ N(0, S_a)`` with the rule applied to each (a fixed ``seed``: common random numbers across designs). The
closed-form margin ``max(min_delta, se_factor * rms SE)``, with ``rms SE = sqrt(tr(M S_a M) + ||S_b^-1 d_b||^2)``,
is reported next to it.

**The lab's data, not the linearisation's** (``truth_draws``, default 20). The diagnosis scores a new flood with the
linearised predictive densities above, but the lab's flood comes from the truth's actual parameters, which its
calibration knows only up to ``C_a``. Where a design extrapolates beyond what the calibration constrains (the
polymer slugs at twice the salinity: a regime change of the phase behaviour that the calibration coreflood never
visits) the truth's forward runs at parameter draws leave its own linearised prediction far behind, and the truth's
score collapses. So the data sets are ``w = W_a (mu_a(z_j) - mu_a) + e`` with ``z_j ~ N(z_a, C_a)`` (clipped to
the unit box; ``truth_draws`` forward runs per hypothesis and design, shared with ``parameter_draws``' when both
are used) and ``e ~ N(0, I)`` the whitened measurement noise, scored by the linearised densities. The median of the
truth's mean-square whitened misfit over the draws is reported (``truth_dispersion``: about 1 where the design stays
where the calibration constrains the truth). ``truth_draws = 0`` draws ``w ~ N(0, S_a)`` instead (linear-Gaussian).

**Over-dispersion** (``dispersion``, default on): the rule applied is the diagnosis's, whose SE is multiplied by
``sqrt(max(1, phi_a, phi_b))``, ``phi_m`` the mean square of model ``m``'s plain whitened residuals ``w - d_m`` on
the flood (:mod:`~spflow.plugins.gap.verdict`).

**Numerical error** (``numerical``, a :class:`~spflow.plugins.gap.numerical_error.NumericalTerm`): the diagnosis's
error model holds the simulator's own numerical error, scaled by ``s`` (:mod:`~spflow.plugins.gap.numerical_error`);
on a design the spread of the base model's predictions over the alternative numerics is measured at the
calibrated base point and added to ``W_a`` the same way (a regime change that the numerics resolve differently
separates nothing then).

Not simulated: the held-out coreflood the diagnosis already has (scored together with the new one), the
generic-discrepancy competitor, the base model as a competitor and the recalibration when the flood joins the
calibration data (docs/next_experiment.md, "Where it is blind").

Designs are ranked (``criterion``) by their worst hypothesis (maximin): the smallest decision accuracy over the
hypotheses (``"accuracy"``), by the accuracy averaged over equally likely hypotheses (``"mean_accuracy"``), or by
the smallest expected log ratio over pairs (``"expected"``: the Box-Hill / KL choice that ignores the spread).
Simulated accuracies equal to two decimals (their Monte Carlo precision at the default 4000 draws; in particular
accuracies saturated at 1) are ties, broken by the smallest expected log ratio.

Failed forward runs leave the design's scores NaN (ranked last) and are counted in its ``failed_runs``.
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, replace

import numpy as np
import xarray as xr

from spflow.core.errors import ParameterError, SpflowError
from spflow.io.format import schedule_json
from spflow.plugins.forward.parameters import resolve_params
from spflow.plugins.forward.run_arguments import output_grid
from spflow.synthetic.core_volumes import pore_volume_ml

from .base_model import BaseModel
from .design_space import Design, design_space
from .layout import make_layout
from .least_squares import Fit, model_point
from .numerical_error import NumericalTerm, inflate
from .observed import Experiment
from .prediction import Predictor
from .quantification import parameter_covariance, raw_jacobian

__all__ = ["Hypothesis", "LogRatioMoments", "hypotheses_from_fits", "log_ratio_moments", "decision_power",
           "rank_designs", "CRITERIA"]

CRITERIA = ("accuracy", "mean_accuracy", "expected")


@dataclass(frozen=True)
class Hypothesis:
    """A competing calibrated model: its name (e.g. ``"base+permeability_reduction"``), its fit, the covariance of
    the fit's unit-box coordinates ``fit.z`` (``None``: no parameter uncertainty) and the base model the fit
    belongs to (``None``: the base shared by all hypotheses, :func:`rank_designs`' ``base``). Hypotheses of a
    diagnosis share its base and differ in their freed effects; hypotheses with their own base express fixed
    alternatives (e.g. full shear thinning against none, each with its own calibrated viscosity law)."""

    name: str
    fit: Fit
    covariance: np.ndarray | None = None
    base: BaseModel | None = None

    def __post_init__(self):
        if self.covariance is not None:
            c = np.asarray(self.covariance, float)
            q = self.fit.z.size
            if c.shape != (q, q) or not np.all(np.isfinite(c)):
                raise ParameterError(f"hypothesis {self.name!r}: covariance must be a finite ({q}, {q}) matrix "
                                     f"over the fit's coordinates, got shape {c.shape}")
            object.__setattr__(self, "covariance", c)


def hypotheses_from_fits(fits: Mapping[str, Fit], tau: float = 0.5,
                         bases: Mapping[str, BaseModel] | None = None) -> list[Hypothesis]:
    """Hypotheses from a diagnosis's fits (name -> :class:`Fit`), each with the linearised covariance of its
    calibration (whitened Jacobian at the optimum, Gaussian prior of scale ``tau`` in the unit box, as in the
    diagnosis's predictive scores) and its base model from ``bases`` (default: the shared base)."""
    bases = bases or {}
    return [Hypothesis(name, f, parameter_covariance(f.jacobian, tau), bases.get(name)) for name, f in fits.items()]


@dataclass(frozen=True)
class LogRatioMoments:
    """Closed-form moments of the log predictive ratio of the truth over an alternative under the truth (nat):
    mean (the KL divergence), standard deviation, root-mean-square measurement SE and the decision margin."""

    expected: float
    sd: float
    se: float
    margin: float


def log_ratio_moments(shift: np.ndarray, s_true: np.ndarray, s_alt: np.ndarray, *, min_delta: float = 4.0,
                      se_factor: float = 2.0) -> LogRatioMoments:
    """Moments of ``log N(w; 0, s_true) - log N(w; shift, s_alt)`` for ``w ~ N(0, s_true)`` and the decision
    margin ``max(min_delta, se_factor * rms SE)`` (module docstring)."""
    shift = np.asarray(shift, float)
    n = shift.size
    sa_inv = np.linalg.inv(s_true)
    sb_inv = np.linalg.inv(s_alt)
    logdet = np.linalg.slogdet(s_alt)[1] - np.linalg.slogdet(s_true)[1]
    b_shift = sb_inv @ shift
    expected = 0.5 * (np.trace(sb_inv @ s_true) + shift @ b_shift - n + logdet)
    ms = (sb_inv - sa_inv) @ s_true
    var = 0.5 * np.trace(ms @ ms) + b_shift @ s_true @ b_shift
    se = math.sqrt(max(float(np.trace(ms @ (sb_inv - sa_inv)) + b_shift @ b_shift), 0.0))
    return LogRatioMoments(float(expected), math.sqrt(max(float(var), 0.0)), se, float(max(min_delta, se_factor * se)))


def decision_power(shifts: Sequence[np.ndarray], covariances: Sequence[np.ndarray], truth: int, *,
                   min_delta: float = 4.0, se_factor: float = 2.0, draws: int = 4000, seed: int = 0,
                   truth_offsets: np.ndarray | None = None,
                   dispersion: bool = False) -> tuple[np.ndarray, float]:
    """Simulated power of the decision rule when hypothesis ``truth`` is true, hypothesis ``m`` predicting
    ``N(shifts[m], covariances[m])`` in the truth's whitened coordinates. Returns, per hypothesis ``b``,
    ``P(L_tb > min_delta and L_tb > se_factor * sqrt(phi) * ||S_t^-1 (w - d_t) - S_b^-1 (w - d_b)||)`` (NaN at
    ``b = truth``) and the probability that the truth passes against every alternative at once (its decision
    accuracy). ``seed`` fixes the draws (common random numbers across designs).

    The data: ``w ~ N(0, S_truth)`` (the truth's own predictive distribution), or, with ``truth_offsets`` (a
    ``(K, n)`` array: the whitened deviations of the truth's forward runs at ``K`` parameter draws from its own
    prediction), ``w = offset_(j mod K) + e_j`` with ``e_j ~ N(0, I)``: the truth's parameters drawn and run through
    the forward model, measurement noise added -- what the lab's coreflood is when the truth's prediction is not
    linear in its parameters, scored by the linearised predictive densities the diagnosis uses. ``phi = 1``, or with
    ``dispersion`` the diagnosis's over-dispersion correction ``max(1, phi_t, phi_b)``, ``phi_m`` the mean square of
    the plain whitened residuals ``w - d_m`` of model ``m`` (:mod:`~spflow.plugins.gap.verdict`)."""
    k = len(shifts)
    n = np.asarray(shifts[truth]).size
    rng = np.random.default_rng(seed)
    if truth_offsets is None:
        w = rng.standard_normal((draws, n)) @ np.linalg.cholesky(covariances[truth]).T
    else:
        offsets = np.asarray(truth_offsets, float)
        if offsets.ndim != 2 or offsets.shape[1] != n or not offsets.shape[0]:
            raise ParameterError(f"truth_offsets must be a (K >= 1, {n}) array, got shape {offsets.shape}")
        w = offsets[np.arange(draws) % offsets.shape[0]] + rng.standard_normal((draws, n))
    logp, grad, phi = [], [], []
    for d, s in zip(shifts, covariances):
        factor = np.linalg.cholesky(s)
        r = w - np.asarray(d)[None, :]
        u = np.linalg.solve(factor, r.T)
        logp.append(-0.5 * np.sum(u**2, axis=0) - np.sum(np.log(np.diag(factor))))
        grad.append(np.linalg.solve(factor.T, u).T)
        phi.append(np.mean(r**2, axis=1) if dispersion else np.ones(draws))
    power = np.full(k, np.nan)
    every = np.ones(draws, bool)
    for b in range(k):
        if b == truth:
            continue
        ratio = logp[truth] - logp[b]
        se = np.linalg.norm(grad[truth] - grad[b], axis=1) * np.sqrt(np.maximum(np.maximum(phi[truth], phi[b]), 1.0))
        ok = (ratio > min_delta) & (ratio > se_factor * se)
        power[b] = float(ok.mean())
        every &= ok
    return power, float(every.mean())


def _base_rate(reference: Experiment) -> tuple[float, str]:
    if "QINJ" in reference.core:
        return float(reference.core["QINJ"]), "the reference coreflood's qinj_ml_min"
    return float(resolve_params({})["QINJ"]), "the forward model's default QINJ (the reference gives none)"


def _design_experiment(reference: Experiment, design: Design, name: str, variables: Sequence[str]) -> Experiment:
    """The reference coreflood's core and measurement chain under ``design``'s schedule (placeholder data)."""
    pv = output_grid(design.schedule.total_pv, reference.pv_step)
    return replace(reference, name=name, schedule=design.schedule, pv=pv,
                   observed={v: np.zeros(pv.size) for v in variables})


def _draw_deviations(predictor: Predictor, layout, h: Hypothesis, draws: int,
                     seed: int) -> tuple[np.ndarray, np.ndarray]:
    """(prediction at the fit, whitened deviations ``(n, K)`` of the predictions at ``draws`` parameter draws
    ``N(z, C)`` (clipped to the unit box; seeded by ``seed``) from it, ``K`` the draws whose runs did not fail).
    The prediction is NaN if its run failed."""
    rng = np.random.default_rng(seed)
    zs = np.clip(rng.multivariate_normal(h.fit.z, h.covariance, size=draws, method="eigh"), 0.0, 1.0)
    points = [h.fit.point] + [model_point(z, h.fit.n_params, h.fit.candidates) for z in zs]
    preds = predictor.predict(points, layout.experiments, layout.variables)
    if preds[0] is None:
        return np.full(layout.size, np.nan), np.zeros((layout.size, 0))
    mu = layout.vector(preds[0])
    done = [layout.whiten(layout.vector(p) - mu) for p in preds[1:] if p is not None]
    return mu, np.column_stack(done) if done else np.zeros((layout.size, 0))


def _parameter_spread(predictor: Predictor, layout, h: Hypothesis, draws: int, diff_step: float,
                      seed: int) -> tuple[np.ndarray, np.ndarray]:
    """(prediction at the fit, whitened spread ``A`` with ``A A'`` the parameter part of the predictive
    covariance): linearised ``W J C^1/2``, or, with ``draws > 0``, the whitened deviations of the predictions at
    ``draws`` parameter draws ``N(z, C)`` (clipped to the unit box) from the fit's, over ``sqrt(draws)`` -- a second
    moment that keeps what the linearisation misses (a regime change between the draws)."""
    if not draws:
        mu, jac = raw_jacobian(predictor, layout, h.fit, diff_step)
        eigval, eigvec = np.linalg.eigh(h.covariance)
        return mu, layout.whiten(jac) @ (eigvec * np.sqrt(np.clip(eigval, 0.0, None)))
    mu, dev = _draw_deviations(predictor, layout, h, draws, seed)
    if not dev.shape[1]:  # every draw failed: no usable spread
        return mu, np.full((layout.size, 1), np.nan)
    return mu, dev / np.sqrt(dev.shape[1])


def _slug_shares(layout, exp: Experiment, shift: np.ndarray, s_alt: np.ndarray) -> dict[str, float]:
    """Shares of the mean-shift term ``d' S^-1 d`` of the log ratio by slug of ``exp`` (sums to 1; slugs with a
    share below 0.005 left out), largest first."""
    terms = shift * np.linalg.solve(s_alt, shift)
    total = terms.sum()
    slug = np.concatenate([b.slug for b in layout.blocks])
    names = [x.name for x in exp.schedule.slugs]
    shares = {names[j]: float(terms[slug == j].sum() / total) for j in np.unique(slug)} if total > 0 else {}
    return dict(sorted(((n, round(v, 3)) for n, v in shares.items() if abs(v) >= 0.005), key=lambda kv: -kv[1]))


def _duration_h(schedule, q0: float, pv_ml: float) -> float:
    return float(sum(s.pv * pv_ml / (q0 if s.rate_ml_min is None else s.rate_ml_min) for s in schedule.slugs) / 60.0)


def rank_designs(hypotheses: Sequence[Hypothesis], base: BaseModel, reference: Experiment,
                 designs: Sequence[Design] | None = None, *, variables: Sequence[str] = ("dp", "oil_cut"),
                 min_delta: float = 4.0, se_factor: float = 2.0, criterion: str = "accuracy", draws: int = 4000,
                 seed: int = 0, parameter_draws: int = 0, truth_draws: int = 20, dispersion: bool = True,
                 numerical: NumericalTerm | None = None, diff_step: float = 0.01, parallel=None,
                 log: Callable[[str], None] | None = None) -> xr.Dataset:
    """Rank ``designs`` (default: :func:`design_space` of the reference schedule at its rate) by how well they
    separate ``hypotheses`` (at least two, distinct names), each a calibrated point of ``base`` (or of its own
    ``Hypothesis.base``), on a coreflood with
    ``reference``'s core and measurement chain (an :class:`~spflow.plugins.gap.observed.Experiment`, e.g. a
    calibration coreflood of the diagnosis) measuring ``variables``. Returns the ranked table (best design first;
    schema in ``docs/next_experiment.md``)."""
    say = log or (lambda msg: None)
    names = [h.name for h in hypotheses]
    if len(names) < 2 or len(set(names)) != len(names):
        raise ParameterError(f"the next experiment needs at least two hypotheses with distinct names, got {names}")
    if isinstance(draws, bool) or not isinstance(draws, int) or draws < 100:
        raise ParameterError(f"draws must be an integer >= 100 (simulated data sets per hypothesis), got {draws!r}")
    if not (math.isfinite(min_delta) and min_delta >= 0.0 and math.isfinite(se_factor) and se_factor >= 0.0):
        raise ParameterError(f"min_delta and se_factor must be finite and >= 0, got {min_delta!r}, {se_factor!r}")
    if isinstance(parameter_draws, bool) or not isinstance(parameter_draws, int) or parameter_draws < 0:
        raise ParameterError(f"parameter_draws must be an integer >= 0 (0: linearised), got {parameter_draws!r}")
    if isinstance(truth_draws, bool) or not isinstance(truth_draws, int) or not 0 <= truth_draws <= draws:
        raise ParameterError(f"truth_draws must be an integer in [0, draws = {draws}] (0: the truth's data from its "
                             f"linearised predictive distribution), got {truth_draws!r}")
    if criterion not in CRITERIA:
        raise ParameterError(f"criterion must be one of {list(CRITERIA)}, got {criterion!r}")
    if numerical is not None and not (math.isfinite(numerical.scale) and numerical.scale >= 0.0):
        raise ParameterError(f"numerical.scale must be finite and >= 0 (the numerical-error term's scale), got "
                             f"{numerical.scale!r}")
    unmeasured = sorted(set(variables) - set(reference.observed))
    if not variables or unmeasured:
        raise ParameterError(f"variables {unmeasured or list(variables)} are not measured in the reference coreflood "
                             f"{reference.name!r} (it has {sorted(reference.observed)})")
    for h in hypotheses:
        own = h.base or base
        if h.fit.n_params != len(own.parameters):
            raise ParameterError(f"hypothesis {h.name!r} has {h.fit.n_params} calibrated parameters; its base model "
                                 f"has {len(own.parameters)} ({', '.join(own.labels)})")
    q0, rate_source = _base_rate(reference)
    say(f"next experiment: base rate {q0:g} ml/min ({rate_source}); noise model "
        f"{'from the reference data' if reference.noise_from_data else 'the documented lab defaults'}")
    designs = list(design_space(reference.schedule, q0) if designs is None else designs)
    if not designs:
        raise ParameterError("the design space is empty")
    exps = [_design_experiment(reference, d, f"design_{i}", variables) for i, d in enumerate(designs)]
    predictors = [Predictor(h.base or base, exps, parallel) for h in hypotheses]
    k, nd = len(hypotheses), len(designs)
    moments = {key: np.full((nd, k, k), np.nan) for key in ("expected", "sd", "se", "margin")}
    power = np.full((nd, k, k), np.nan)
    accuracy = np.full((nd, k), np.nan)
    truth_phi = np.full((nd, k), np.nan)
    where = np.full((nd, k, k), None, dtype=object)
    failed = np.zeros(nd, int)
    points = np.zeros(nd, int)
    numerical_runs = 0
    for i, (design, exp) in enumerate(zip(designs, exps)):
        say(f"design {i + 1}/{nd}: {design.label}")
        preds = [p.predict([h.fit.point], [exp.name], list(variables))[0] for p, h in zip(predictors, hypotheses)]
        if any(p is None for p in preds):
            failed[i] = sum(p is None for p in preds)
            continue
        numerics = None
        if numerical is not None and numerical.scale > 0.0:
            own = Predictor(base, [exp], parallel)
            try:  # the diagnosis's numerical-error term on this design (its base model at other numerics)
                term = numerical.spread(own)
            except SpflowError:
                failed[i] = k
                continue
            numerics, numerical_runs = term.series, numerical_runs + term.runs + own.runs
        series = [p[exp.name] for p in preds]
        common = {v: np.all([np.isfinite(s[v]) for s in series], axis=0) for v in variables}
        for a in range(k):
            # the true hypothesis's predictions are the data (its error model is scaled from them); every
            # hypothesis is compared on the points all of them predict
            observed = {v: np.where(common[v], series[a][v], np.nan) for v in variables}
            layout = make_layout([replace(exp, observed=observed)], list(variables))
            if numerics is not None:
                layout = inflate(layout, numerics, numerical.scale)
            points[i] = layout.size
            mu_a = layout.observed()
            shifts, covs = [], []
            for m, h in enumerate(hypotheses):
                if h.covariance is None:
                    mu, s = layout.vector({exp.name: series[m]}), np.eye(layout.size)
                else:
                    mu, spread = _parameter_spread(predictors[m], layout, h, parameter_draws, diff_step, seed + m)
                    s = np.eye(layout.size) + spread @ spread.T
                shifts.append(layout.whiten(mu - mu_a))
                covs.append(s)
            offsets = None
            if truth_draws and hypotheses[a].covariance is not None:
                # the truth's data: its forward runs at parameter draws (same seed as its spread: memoised runs)
                offsets = _draw_deviations(predictors[a], layout, hypotheses[a], truth_draws, seed + a)[1].T
                if offsets.shape[0]:
                    truth_phi[i, a] = 1.0 + float(np.median(np.mean(offsets**2, axis=1)))
            if not all(np.all(np.isfinite(x)) for x in shifts + covs) or (offsets is not None
                                                                          and not offsets.shape[0]):
                failed[i] += 1
                continue
            for b in range(k):
                if b != a:
                    r = log_ratio_moments(shifts[b] - shifts[a], covs[a], covs[b], min_delta=min_delta,
                                          se_factor=se_factor)
                    for key in moments:
                        moments[key][i, a, b] = getattr(r, key)
                    where[i, a, b] = _slug_shares(layout, exp, shifts[b] - shifts[a], covs[b])
            power[i, a], accuracy[i, a] = decision_power(shifts, covs, a, min_delta=min_delta, se_factor=se_factor,
                                                         draws=draws, seed=seed, truth_offsets=offsets,
                                                         dispersion=dispersion)
    off = ~np.eye(k, dtype=bool)
    usable = np.all(np.isfinite(accuracy), axis=1)

    def over_pairs(values, reduce):
        return np.array([reduce(values[i][off]) if usable[i] else np.nan for i in range(nd)])

    worst_accuracy = np.where(usable, np.min(accuracy, axis=1), np.nan)
    mean_accuracy = np.where(usable, np.mean(accuracy, axis=1), np.nan)
    worst_power = over_pairs(power, np.min)
    worst_expected = over_pairs(moments["expected"], np.min)
    worst_where = [json.dumps(where[i][off][int(np.argmin(moments["expected"][i][off]))]) if usable[i] else "{}"
                   for i in range(nd)]
    key = {"accuracy": worst_accuracy, "mean_accuracy": mean_accuracy, "expected": worst_expected}[criterion]
    # simulated accuracies are good to about 0.01: equal at two decimals is a tie, broken by the worst expected
    # log ratio (the larger, the more the design separates beyond the decision margin)
    order = sorted(range(nd), key=lambda i: (not usable[i], -round(key[i], 2) if usable[i] else 0.0,
                                             -worst_expected[i] if usable[i] else 0.0, i))
    pv_ml = reference.pore_volume_ml or pore_volume_ml(resolve_params(reference.core))

    def per_design(values):
        return np.asarray(values)[order]

    dims3 = ("design", "truth", "alternative")
    ds = xr.Dataset(
        {
            "expected_log_ratio": (dims3, moments["expected"][order], {
                "units": "1", "long_name": "expected held-out log predictive ratio (nats) of the truth over the "
                "alternative (KL divergence of their predictive distributions)"}),
            "log_ratio_sd": (dims3, moments["sd"][order], {"units": "1", "long_name": "its standard deviation (nats)"}),
            "decision_margin": (dims3, moments["margin"][order], {
                "units": "1", "long_name": "decision margin (nats): max(min_delta, se_factor x root-mean-square measurement SE)"}),
            "power": (dims3, power[order], {
                "units": "1", "long_name": "probability that the decision rule prefers the truth over the "
                "alternative (simulated)"}),
            "accuracy": (("design", "truth"), accuracy[order], {
                "units": "1", "long_name": "probability that the truth beats every alternative (simulated)"}),
            "truth_dispersion": (("design", "truth"), truth_phi[order], {
                "units": "1", "long_name": "median over the truth's parameter draws of the mean square of its "
                "whitened data about its own prediction at the fit (1 + noise-free part; about 1 when the design "
                "stays where the calibration constrains the truth)"}),
            "worst_accuracy": ("design", per_design(worst_accuracy), {
                "units": "1", "long_name": "smallest decision accuracy over the hypotheses"}),
            "mean_accuracy": ("design", per_design(mean_accuracy), {
                "units": "1", "long_name": "decision accuracy averaged over equally likely hypotheses"}),
            "worst_power": ("design", per_design(worst_power), {"units": "1", "long_name": "smallest pair power"}),
            "worst_expected_log_ratio": ("design", per_design(worst_expected), {
                "units": "1", "long_name": "smallest expected log predictive ratio over pairs (nats)"}),
            "rank": ("design", np.arange(1, nd + 1), {"units": "1", "long_name": f"rank by {criterion} (1 = best)"}),
            "label": ("design", np.array([designs[i].label for i in order], dtype=object)),
            "kind": ("design", np.array([designs[i].kind for i in order], dtype=object)),
            "schedule": ("design", np.array([schedule_json(designs[i].schedule) for i in order], dtype=object),
                         {"long_name": "schedule JSON (spflow.io.format.schedule_json)"}),
            "total_pv": ("design", per_design([d.schedule.total_pv for d in designs]),
                         {"units": "1", "long_name": "injected pore volumes"}),
            "duration": ("design", per_design([_duration_h(d.schedule, q0, pv_ml) for d in designs]),
                         {"units": "h", "long_name": "injection time at the design's rates"}),
            "n_points": ("design", per_design(points), {"units": "1", "long_name": "measured points compared"}),
            "separation_by_slug": ("design", np.array([worst_where[i] for i in order], dtype=object), {
                "long_name": "JSON {slug: share of the mean-shift term d' S^-1 d} of the pair with the smallest "
                "expected log ratio: which slugs of the design separate the hypotheses"}),
            "failed_runs": ("design", per_design(failed), {"units": "1",
                                                           "long_name": "hypotheses whose forward runs failed"}),
        },
        coords={"design": np.arange(nd), "truth": names, "alternative": names},
        attrs={
            "criterion": criterion,
            "hypotheses": json.dumps(names),
            "reference_experiment": reference.name,
            "variables": json.dumps(list(variables)),
            "min_delta": float(min_delta),
            "draws": int(draws),
            "seed": int(seed),
            "se_factor": float(se_factor),
            "base_rate_ml_min": q0,
            "base_rate_source": rate_source,
            "noise_model_source": "reference data" if reference.noise_from_data else "documented lab defaults",
            "parameter_uncertainty": json.dumps({h.name: h.covariance is not None for h in hypotheses}),
            "parameter_uncertainty_method": (f"Monte Carlo over {parameter_draws} parameter draws" if parameter_draws
                                             else "linearised (forward-difference Jacobian)"),
            "truth_draws": int(truth_draws),
            "dispersion_correction": int(bool(dispersion)),
            "truth_data": (f"the truth's forward runs at {truth_draws} parameter draws from its calibration "
                           "covariance plus measurement noise" if truth_draws else
                           "the truth's linearised predictive distribution"),
            "forward_runs": int(sum(p.runs for p in predictors)) + numerical_runs,
            "numerical_error": (f"the diagnosis's numerical-error term, scale {numerical.scale:.3g}, spread over "
                                f"{len(numerical.variants)} alternative numerics at the calibrated base point"
                                if numerical is not None and numerical.scale > 0.0 else "none"),
            "method": "Gaussian predictive distributions under the diagnosis's error model with linearised "
                      "parameter uncertainty; expected log ratio = KL divergence; power and accuracy simulated with "
                      "the decision rule (spflow.plugins.gap.next_experiment)",
        },
    )
    return ds
