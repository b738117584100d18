"""The decision rule of a gap diagnosis (docs/gap.md, Method: **Decision**).

A refitted candidate *passes* when its out-of-sample gain is large and significant, its strength is physical and
significantly different from the base strength (the effect is present: the "scaling factor != 0" of detection in
climate attribution), and the calibration data ask for it:

    dELPD > min_delta (4)  and  dELPD > se_factor (2) * SE  and  dist(v_hat, physical range) <= physical_tolerance
    (2) * sd(v_hat)  and  |v_hat - v_base| > se_factor * sd(v_hat)  and  chi2_ref - chi2_k > min_chi2_drop,

with ``v`` the strength's unit-box coordinate and ``sd`` its linearised posterior standard deviation from the
refit (:func:`~spflow.plugins.gap.quantification.parameter_covariance`). The physical test asks whether the
estimate is *consistent* with a physical strength, not whether the point estimate lies inside the range: a truth
at the edge of the range (the twin study's salinity exponent x1.5) is fitted beyond it in about half of the noise
realisations, and the strict test (``physical_tolerance = 0``) turned those into ``out_of_catalogue``. The strength test matters: a refit that
leaves the strength at its base value can still predict held-out data better, only because its calibrated
parameters landed elsewhere. The last test is the nested likelihood-ratio test on the calibration data (the refit
contains the reference at the base strength; ``min_chi2_drop`` is the chi^2_1 quantile at the diagnosis's
``alpha``): an effect the calibration data do not ask for is not added, in particular not as a second effect on
top of a first one whose fit left some misfit. (An effect that is off in the base model can only be added with
``s >= 0``, so the sign test of the rule is the physical range.)

**Competitors** (issue 20). With held-out data, a candidate must also beat the generic-discrepancy competitor
(:mod:`~spflow.plugins.gap.discrepancy`: a smooth per-slug discrepancy fitted on the calibration data,
transferred as its per-slug-type mean) by the same margins, ``dELPD_k - dELPD_disc > min_delta`` and
``> se_factor * SE``; the other competitor, the simulator's own numerical error, is inside every model's
covariance (:mod:`~spflow.plugins.gap.numerical_error`). A candidate that closes the calibration gap but does not
beat them is *tried, not declared*.

**Over-dispersion.** The measurement SE assumes the model is right up to measurement noise. Where a model leaves
held-out misfit far above the noise (whitened mean square ``phi = chi^2 / n > 1``), every SE of its comparisons
is multiplied by ``sqrt(phi)`` (the quasi-likelihood dispersion correction): two wrong models whose scores differ
by a few percent of thousands of nats are not told apart by noise-sized SEs.

The **ambiguity set** is the best passing candidate plus every physical candidate whose gain is within
``se_factor`` (dispersion-corrected) standard errors of the best one's, with the measurement SE of their
difference (:mod:`~spflow.plugins.gap.predictive_scores`), whether or not it passes on its own: candidates whose
scores are not separated beyond the SE are one set. One member is an ``effect``, several are ``ambiguous`` (an
effect accepted in a later step is no longer ambiguous with the first one: the answer is "both"). The pointwise
SE of ``loo_compare`` was tried for the set and rejected: it put a candidate that closed 0.1 % of the bundled
data's calibration gap in one set with the one that closed 54 %, because for localised gaps that SE is of the
order of the gains themselves. Several effects are searched for jointly (:mod:`~spflow.plugins.gap.subsets`):
every member of the final set must pass the same test against the set without it.

**Gap significance.** The calibration gap is significant when either of two tests at level ``alpha`` rejects
the base model (with the numerical error in the covariance): the omnibus test ``P(chi^2_{n-p} >= chi^2_base) <
alpha``, or the targeted test (:func:`targeted_pvalue`): the largest calibration-misfit drop of a refitted
candidate, Bonferroni-adjusted over the catalogue. The omnibus test spreads its power over every direction of the
``n - p`` residual space; a catalogue effect concentrates its misfit on one direction, and a drop of 40 in chi^2
on 70 points can leave the omnibus p at 0.3. In the twin study (v5) 14 single-effect twins whose true effect
passed every other test out of sample (dELPD 15-170) ended ``none`` on the omnibus test alone. Together the two
tests reject a base model that holds with probability at most ``2 alpha``.

The final verdict needs a significant calibration gap for anything but ``none``:

* ``effect`` / ``ambiguous`` — a set passed (against the base, the discrepancy competitor and, per member,
  the set without it) and the final model closes at least ``closed_fraction`` (half) of the calibration gap
  (not applicable when only the targeted test finds the gap: the base misfit is then below its noise
  expectation and the fraction closed is undefined);
* ``unattributed`` — the gap is real, physical candidates close half of it on the calibration data (for a gap
  only the targeted test finds: a physical candidate whose own misfit drop is significant on that test), but none
  predicts the held-out coreflood better than the base and the competitors: not attributable to a catalogued
  mechanism (the report shows the gap's size and where it is; the candidates are "tried, not declared");
* ``out_of_catalogue`` — a calibration gap that no candidate (or accepted combination) closes by half;
* ``none`` — no significant calibration gap. Gains that show only out of sample are reported, not declared: a
  base model calibrated on few corefloods has several parameter optima that fit them equally well and predict
  other floods differently, and a refit that lands in another optimum wins out of sample with or without its
  effect (on null twins, a refit whose strength went back to the base value gained 70 nats on the held-out flood).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

__all__ = ["Rule", "CandidateScore", "significant", "passes", "ambiguity_set", "targeted_pvalue", "verdict",
           "VERDICTS"]

#: every verdict a diagnosis can return
VERDICTS = ("none", "effect", "ambiguous", "unattributed", "out_of_catalogue")


@dataclass(frozen=True)
class Rule:
    """Thresholds of the decision rule."""

    min_delta: float = 4.0
    se_factor: float = 2.0
    closed_fraction: float = 0.5
    min_chi2_drop: float = 6.635  # chi^2_1 quantile at 0.01
    #: how many linearised posterior sd a fitted strength may lie outside its effect's physical range and still
    #: count as physical (0: the point estimate must lie inside it)
    physical_tolerance: float = 2.0


@dataclass(frozen=True)
class CandidateScore:
    """Scores of one refitted candidate against its reference model; ``gradient`` is its ``S^-1 w`` on the
    held-out points (:mod:`~spflow.plugins.gap.predictive_scores`), for the pairwise SE of the ambiguity set."""

    name: str
    delta_elpd: float
    se: float
    se_pointwise: float
    strength: float
    strength_z: float
    physical: bool
    gap_closed: float
    chi2_drop: float
    gradient: np.ndarray
    competitor_delta: float = float("nan")
    competitor_se: float = float("nan")
    dispersion: float = 1.0


def significant(delta: float, se: float, dispersion: float, rule: Rule) -> bool:
    """``delta > min_delta`` and ``delta > se_factor * sqrt(dispersion) * se`` (module docstring)."""
    return bool(np.isfinite(delta) and delta > rule.min_delta
                and delta > rule.se_factor * np.sqrt(max(dispersion, 1.0)) * se)


def passes(score: CandidateScore, rule: Rule) -> bool:
    """The decision rule for one candidate against its reference (and the competitor, when scored)."""
    beats_competitor = (not np.isfinite(score.competitor_se)
                        or significant(score.competitor_delta, score.competitor_se, score.dispersion, rule))
    return bool(significant(score.delta_elpd, score.se, score.dispersion, rule) and beats_competitor
                and score.physical and abs(score.strength_z) > rule.se_factor
                and score.chi2_drop > rule.min_chi2_drop)


def ambiguity_set(scores: Sequence[CandidateScore], rule: Rule) -> list[CandidateScore]:
    """The best passing candidate and every physical candidate within ``se_factor`` (dispersion-corrected) SE of
    it (best first); empty if none passes."""
    passing = sorted((s for s in scores if passes(s, rule)), key=lambda s: -s.delta_elpd)
    if not passing:
        return []
    best = passing[0]
    out = [best]
    for s in sorted(scores, key=lambda s: -s.delta_elpd):
        if s is best or not s.physical or not np.isfinite(s.delta_elpd):
            continue
        ok = np.isfinite(best.gradient) & np.isfinite(s.gradient)
        se = float(np.linalg.norm(best.gradient[ok] - s.gradient[ok]))
        if best.delta_elpd - s.delta_elpd <= rule.se_factor * np.sqrt(max(best.dispersion, s.dispersion, 1.0)) * se:
            out.append(s)
    return out


def targeted_pvalue(chi2_drops: Sequence[float], n_candidates: int) -> float:
    """The targeted test of the calibration gap: the Bonferroni-adjusted p-value ``min(1, K P(chi^2_1 >= D_max))``
    of the largest nested likelihood-ratio statistic ``D_max = max_k (chi^2_ref - chi^2_k)`` over the refitted
    candidates, ``K`` = ``n_candidates`` the size of the catalogue screened (the shortlist was chosen by looking
    at the data, so the correction counts every candidate). Each ``D_k`` is asymptotically ``chi^2_1`` (a
    strength at the boundary of its range gives the conservative 50:50 mixture of ``chi^2_0`` and ``chi^2_1``)
    under a base model that holds (module docstring, **Gap significance**). 1 when nothing was refitted."""
    from scipy.stats import chi2  # (the stage table imports Rule from here: ``spflow list`` loads no SciPy)

    drops = [d for d in chi2_drops if np.isfinite(d)]
    if not drops or n_candidates < 1:
        return 1.0
    return float(min(1.0, n_candidates * chi2.sf(max(max(drops), 0.0), 1)))


def verdict(steps: Sequence[Sequence[str]], gap_significant: bool, final_closed: float,
            closers: Sequence[str], rule: Rule) -> tuple[str, list[str]]:
    """(verdict, ambiguity set) from the accepted steps (each step's ambiguity set, best first), whether the
    calibration gap is significant, the gap fraction closed by the final model (NaN when the base misfit is below
    its noise expectation: the gap then shows only along candidate directions and the fraction is not defined),
    and the physical candidates that close half the calibration gap without passing out of sample (module
    docstring)."""
    if not gap_significant:
        return "none", []
    if steps:
        if np.isfinite(final_closed) and final_closed < rule.closed_fraction:
            return "out_of_catalogue", []
        return ("ambiguous" if any(len(s) > 1 for s in steps) else "effect"), list(steps[0])
    return ("unattributed", []) if closers else ("out_of_catalogue", [])
