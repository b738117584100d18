"""Joint search for several coexisting effects: every subset of a shortlisted pool, then backward elimination.

Greedy forward selection adds the best single effect and then the best effect on top of it. It fails when two
effects compensate each other: Dawson & Lantz's inaccessible pore volume opposes adsorption at the polymer front,
so each alone fits *worse* than the base model plus a wrong one, and the pair that explains the data is never
tried (issue 20: three withheld effects ended ``out_of_catalogue`` with nothing added). Here every subset of
at most ``max_size`` effects of a small pool (the candidates that the single-effect step shortlisted, ranked by
their single-effect scores) is refitted jointly, and a subset ``S`` is **admissible** when every member earns its
place: the decision rule (:func:`~spflow.plugins.gap.verdict.significant` and the strength tests) holds for ``S``
against ``S`` without that member -- backward elimination, applied to every member, on the held-out score and on
the calibration chi^2 (nested likelihood-ratio test) -- and ``S`` as a whole beats every competitor (the
generic discrepancy) by the same margins. The search returns the admissible subset with the best held-out score
(ties: the smaller set). Cost: one joint refit per subset, ``sum_{k<=max_size} C(pool, k)`` refits (14 for a
pool of 4 and triples), each warm-started from the single-effect fits.

:func:`forward_selection` is the greedy path on the same scores, kept for comparison (the tests build a case it
provably misses).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from itertools import combinations

import numpy as np

from .predictive_scores import Predictive, compare
from .verdict import Rule, significant

__all__ = ["SubsetFit", "SearchResult", "subset_key", "needed", "admissible", "best_subset", "forward_selection"]


@dataclass
class SubsetFit:
    """A model with the effects ``names`` freed and fitted jointly: calibration chi^2, fitted strengths, their
    z against the base strength, whether each is physical, and the out-of-sample predictive terms."""

    names: tuple[str, ...]
    chi2: float
    strengths: dict[str, float]
    strength_z: dict[str, float]
    physical: dict[str, bool]
    predictive: Predictive

    @property
    def dispersion(self) -> float:
        """Mean squared whitened out-of-sample residual (>= 1: the over-dispersion of verdict.py)."""
        w = self.predictive.whitened[np.isfinite(self.predictive.whitened)]
        return max(1.0, float(np.mean(w**2))) if w.size else 1.0


@dataclass
class SearchResult:
    """The chosen subset (``()``: none admissible), every fit by subset, and which subsets were admissible."""

    chosen: tuple[str, ...]
    fits: dict[tuple[str, ...], SubsetFit]
    admissible: list[tuple[str, ...]] = field(default_factory=list)


def subset_key(names) -> tuple[str, ...]:
    """The canonical (sorted) key of a set of effect names."""
    return tuple(sorted(names))


def _beats(model: SubsetFit, other: Predictive, rule: Rule) -> bool:
    delta, se, _ = compare(model.predictive, other)
    return significant(delta, se, model.dispersion, rule)


def needed(model: SubsetFit, without: SubsetFit, name: str, rule: Rule) -> bool:
    """Member ``name`` of ``model`` earns its place against ``without`` (``model`` without it): out-of-sample gain,
    calibration chi^2 drop, physical and significantly non-base strength."""
    return bool(_beats(model, without.predictive, rule) and without.chi2 - model.chi2 > rule.min_chi2_drop
                and model.physical[name] and abs(model.strength_z[name]) > rule.se_factor)


def admissible(names: Sequence[str], evaluate: Callable[[tuple[str, ...]], SubsetFit], rule: Rule,
               competitors: Sequence[Predictive] = ()) -> bool:
    """Every member of ``names`` is :func:`needed` and the set beats every competitor (module docstring)."""
    model = evaluate(subset_key(names))
    if not names:
        return False
    if not all(_beats(model, c, rule) for c in competitors):
        return False
    return all(needed(model, evaluate(subset_key(n for n in names if n != name)), name, rule) for name in names)


def best_subset(pool: Sequence[str], evaluate: Callable[[tuple[str, ...]], SubsetFit], rule: Rule,
                max_size: int = 3, competitors: Sequence[Predictive] = ()) -> SearchResult:
    """The admissible subset of ``pool`` (at most ``max_size`` effects) with the best out-of-sample score;
    ``evaluate`` fits a subset (it is called for ``()``, the base model, too) and should memoise."""
    fits: dict[tuple[str, ...], SubsetFit] = {}

    def memo(names: tuple[str, ...]) -> SubsetFit:
        if names not in fits:
            fits[names] = evaluate(names)
        return fits[names]

    ok = []
    for size in range(1, min(max_size, len(pool)) + 1):
        for names in combinations(sorted(pool), size):
            if admissible(names, memo, rule, competitors):
                ok.append(names)
    chosen = max(ok, key=lambda n: (memo(n).predictive.total, -len(n))) if ok else ()
    return SearchResult(chosen, fits, ok)


def forward_selection(pool: Sequence[str], evaluate: Callable[[tuple[str, ...]], SubsetFit], rule: Rule,
                      max_size: int = 3, competitors: Sequence[Predictive] = ()) -> tuple[str, ...]:
    """Greedy path: add the best effect that is needed on top of the current set (and beats the competitors)
    until none is."""
    current: tuple[str, ...] = ()
    while len(current) < max_size:
        best = None
        for name in pool:
            if name in current:
                continue
            model = evaluate(subset_key(current + (name,)))
            if needed(model, evaluate(subset_key(current)), name, rule) and all(_beats(model, c, rule)
                                                                         for c in competitors):
                if best is None or model.predictive.total > evaluate(subset_key(current + (best,))).predictive.total:
                    best = name
        if best is None:
            return current
        current = subset_key(current + (best,))
    return current
