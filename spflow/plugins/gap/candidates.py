"""Screen, shortlist and refit candidate effects (docs/gap.md, Method: **Which**).

* :func:`fingerprint_columns` — whitened finite-strength responses of each candidate at a calibrated point
  (one forward run per candidate and test strength), the input of
  :func:`~spflow.plugins.gap.fingerprints.screen`;
* :func:`screen_order` — every candidate, best screen score first (the first step's refits by default: the screen
  is linear, and an effect the recalibration bends can rank low although it is the one that fits);
* :func:`shortlist` — the candidates worth a refit: the ``size`` best positive screen scores, plus every candidate
  whose projected fingerprint is near-collinear (cos >= ``cos_threshold``) with one of them (an a-priori ambiguity
  partner), minus those whose fingerprint re-calibration absorbs almost entirely (indistinguishable from a
  calibrated parameter: nothing to attribute);
* :func:`refit` — "reference model + effect": the calibrated parameters, the strengths already in the reference
  and the new strength fitted together, from nested and fresh starts at every test strength (the non-convexity
  guard of docs/gap.md, Method: **Which**).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from spflow.core.errors import SpflowError

from .catalogue import CandidateEffect
from .fingerprints import ScreenResult
from .layout import Layout
from .least_squares import Fit, fit
from .prediction import Predictor

__all__ = ["FIRST_STEP_REFITS", "fingerprint_columns", "screen_order", "shortlist", "refit"]


def fingerprint_columns(predictor: Predictor, layout: Layout, reference: Fit,
                        candidates: Sequence[CandidateEffect]) -> list[np.ndarray]:
    """Per candidate an (n, n_levels) matrix of whitened prediction changes at ``reference``'s point
    (zero columns where the forward run failed)."""
    u, strengths = reference.point
    points = [(u, strengths)] + [(u, {**strengths, c.name: level}) for c in candidates for level in c.levels]
    preds = predictor.predict(points, layout.experiments, layout.variables)
    if preds[0] is None:
        raise SpflowError("the forward run at the calibrated point failed")
    ref = layout.vector(preds[0])
    out, k = [], 1
    for c in candidates:
        cols = []
        for _ in c.levels:
            p = preds[k]
            cols.append(np.zeros(layout.size) if p is None else layout.whiten(layout.vector(p) - ref))
            k += 1
        out.append(np.column_stack(cols))
    return out


#: ``Options.first_step_refits``: every candidate, or the screen's shortlist
FIRST_STEP_REFITS = ("all", "shortlist")


def screen_order(result: ScreenResult) -> list[int]:
    """Indices of all candidates, best screen score first (candidates without a score last)."""
    z = result.best_z()
    return sorted(range(len(z)), key=lambda i: -np.nan_to_num(z[i], nan=-np.inf))


def shortlist(result: ScreenResult, size: int, cos_threshold: float = 0.9, absorbed_max: float = 0.95,
              ) -> list[int]:
    """Indices of the candidates to refit (module docstring), best screen score first."""
    z = result.best_z()
    usable = [i for i in range(len(z)) if result.absorbed(i) < absorbed_max]
    ranked = sorted((i for i in usable if z[i] > 0.0), key=lambda i: -z[i])
    chosen = ranked[:size]
    for i in list(chosen):
        for j in usable:
            if j not in chosen and result.cos[i, j] >= cos_threshold:
                chosen.append(j)
    return chosen


def refit(predictor: Predictor, layout: Layout, reference: Fit, candidate: CandidateEffect,
          fresh: np.ndarray | None = None, *, max_nfev: int = 30, diff_step: float = 0.01,
          economy: bool = True, first_round: str = "difference") -> Fit:
    """The reference model plus ``candidate``, fitted on ``layout``. Starts, with the new strength at each of its
    test strengths: the reference optimum (nested), and, if given, the unit-box parameters ``fresh`` (the base
    calibration's own start) with the reference strengths -- re-calibration with the effect on from scratch,
    because the reference optimum has already bent the parameters to mimic the missing effect. ``economy`` and
    ``first_round``: see :func:`~spflow.plugins.gap.least_squares.fit`."""
    starts = []
    for level in candidate.levels:
        starts.append(np.concatenate((reference.z, [candidate.unit(level)])))
        if fresh is not None:
            starts.append(np.concatenate((fresh, reference.z[reference.n_params:], [candidate.unit(level)])))
    return fit(predictor, layout, starts, reference.candidates + (candidate,), max_nfev=max_nfev,
               diff_step=diff_step, economy=economy, first_round=first_round)
