"""The decision rule of a gap diagnosis (gap notes §6.1 stage 2, step 4).

A refitted candidate *passes* when its out-of-sample gain is large and significant, its strength is physical and
significantly different from the base strength (the effect is present: the "scaling factor != 0" of detection in
climate attribution), and the calibration data ask for it:

    dELPD > min_delta (4)  and  dELPD > se_factor (2) * SE  and  s_hat inside the physical range
    and  |v_hat - v_base| > se_factor * sd(v_hat)  and  chi2_ref - chi2_k > min_chi2_drop,

with ``v`` the strength's unit-box coordinate and ``sd`` its linearised posterior standard deviation from the
refit (:func:`~spflow.plugins.gap.quantification.parameter_covariance`). The strength test matters: a refit that
leaves the strength at its base value can still predict held-out data better, only because its calibrated
parameters landed elsewhere. The last test is the nested likelihood-ratio test on the calibration data (the refit
contains the reference at the base strength; ``min_chi2_drop`` is the chi^2_1 quantile at the diagnosis's
``alpha``): an effect the calibration data do not ask for is not added, in particular not as a second effect on
top of a first one whose fit left some misfit. (An effect that is off in the base model can only be added with
``s >= 0``, so the sign test of the notes is the physical range.)

Among passing candidates the **ambiguity set** is every candidate whose gain is within ``se_factor`` standard
errors of the best one's, with the measurement SE of their difference
(:mod:`~spflow.plugins.gap.predictive_scores`). One member is an ``effect``, several are ``ambiguous`` (an effect
accepted in a later greedy step is no longer ambiguous with the first one: the answer is "both"). The pointwise SE
of ``loo_compare`` was tried for the set and rejected: it put a candidate that closed 0.1 % of the bundled data's
calibration gap in one set with the one that closed 54 %, because for localised gaps that SE is of the order of
the gains themselves, and on the twins it never brought a missing true effect into a set. Effects are added
greedily: a second one must pass the same test on top of the first.

The final verdict needs a significant calibration gap for anything but ``none``:

* ``effect`` / ``ambiguous`` — at least one step passed and the final model closes at least ``closed_fraction``
  (half) of the calibration gap;
* ``ambiguous`` also when nothing passes out of sample but some physical candidates close half of the
  calibration gap (the set is those candidates: unconfirmed);
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

__all__ = ["Rule", "CandidateScore", "passes", "ambiguity_set", "verdict"]


@dataclass(frozen=True)
class Rule:
    """Thresholds of the decision rule."""

    min_delta: float = 4.0
    se_factor: float = 2.0
    closed_fraction: float = 0.5
    min_chi2_drop: float = 6.635  # chi^2_1 quantile at 0.01


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


def passes(score: CandidateScore, rule: Rule) -> bool:
    d = score.delta_elpd
    return bool(np.isfinite(d) and d > rule.min_delta and d > rule.se_factor * score.se and score.physical
                and abs(score.strength_z) > rule.se_factor and score.chi2_drop > rule.min_chi2_drop)


def ambiguity_set(scores: Sequence[CandidateScore], rule: Rule) -> list[CandidateScore]:
    """Passing candidates within ``se_factor`` SE of the best passing one (best first); empty if none pass."""
    passing = sorted((s for s in scores if passes(s, rule)), key=lambda s: -s.delta_elpd)
    if not passing:
        return []
    best = passing[0]
    out = [best]
    for s in passing[1:]:
        ok = np.isfinite(best.gradient) & np.isfinite(s.gradient)
        se = float(np.linalg.norm(best.gradient[ok] - s.gradient[ok]))
        if best.delta_elpd - s.delta_elpd <= rule.se_factor * se:
            out.append(s)
    return out


def verdict(steps: Sequence[Sequence[str]], gap_significant: bool, final_closed: float,
            unconfirmed: Sequence[str], rule: Rule) -> tuple[str, list[str]]:
    """(verdict, ambiguity set) from the accepted greedy steps (each step's ambiguity set, best first), whether the
    calibration gap is significant, the gap fraction closed by the final model, and the physical candidates that
    close half the calibration gap without passing out of sample."""
    if not gap_significant:
        return "none", []
    if steps:
        if not final_closed >= rule.closed_fraction:
            return "out_of_catalogue", []
        return ("ambiguous" if any(len(s) > 1 for s in steps) else "effect"), list(steps[0])
    return ("ambiguous", list(unconfirmed)) if unconfirmed else ("out_of_catalogue", [])
