"""Uncertainty of the predicted Pareto front: sampled fronts, empirical attainment function, Vorob'ev expectation.

The shaded bands of thesis Figs. 4.7-4.8 (Pandita et al. 2018, docs/eeihv.md §7; Binois, Ginsbourger & Roustant
2015). Each objective's GP posterior of the *latent* objective is sampled jointly at a dense design set (a Latin
hypercube plus the observed designs); the non-dominated subset of each joint draw is one plausible Pareto front.
From the sample of fronts (all with moocore, exact, minimisation):

* the empirical attainment function (EAF) α(z) = fraction of sampled fronts that weakly dominate z; ``eaf`` holds
  its attainment surfaces, the boundary points where α reaches each level (``moocore.eaf``);
* the Vorob'ev expectation Q_β* = {z : α(z) ≥ β*}, with the threshold β* chosen so that the hypervolume of Q_β*
  equals the mean hypervolume of the sampled fronts (``moocore.vorob_t``);
* the Vorob'ev deviation, the expected hypervolume of the symmetric difference between a sampled front's dominated
  set and Q_β* (``moocore.vorob_dev``): it shrinks to 0 as the front becomes certain.

Hypervolumes are bounded by the run's reference point; objectives are minimised.
"""

from __future__ import annotations

from dataclasses import dataclass

import moocore
import numpy as np
from scipy.stats import qmc

from spflow.core.errors import ParameterError

from .bgo_loop import BGOResult
from .pareto_front import nondominated

__all__ = ["FrontUncertainty", "front_uncertainty"]


@dataclass
class FrontUncertainty:
    """Sampled fronts and their summaries.

    ``points`` (m, 2) and ``sets`` (m,) hold the sampled fronts (rows of front j have ``sets == j``); ``eaf``
    (e, 3) the attainment-surface points with their level in percent in the last column; ``vorob_threshold`` β* in
    percent, ``vorob_expectation`` (v, 2) the boundary of Q_β*, ``vorob_hypervolume`` its hypervolume,
    ``vorob_deviation`` the Vorob'ev deviation, ``reference`` (2,) the reference point used.
    """

    points: np.ndarray
    sets: np.ndarray
    eaf: np.ndarray
    vorob_threshold: float
    vorob_expectation: np.ndarray
    vorob_hypervolume: float
    vorob_deviation: float
    reference: np.ndarray

    def attainment_surface(self, percent: float) -> np.ndarray:
        """Points (k, 2) of the attainment surface at level ``percent`` (one of the levels present in ``eaf``)."""
        levels = np.unique(self.eaf[:, 2])
        level = levels[np.argmin(np.abs(levels - percent))]
        if not np.isclose(level, percent):
            raise ParameterError(f"attainment level {percent}% is not one of the EAF levels {levels.tolist()}")
        return self.eaf[self.eaf[:, 2] == level, :2]


def front_uncertainty(result: BGOResult, *, n_fronts: int = 100, n_designs: int = 1000, seed: int = 0,
                      reference: np.ndarray | None = None) -> FrontUncertainty:
    """Sample ``n_fronts`` Pareto fronts from the GP posterior of ``result`` at ``n_designs`` LHS designs plus the
    observed ones and summarise them (module docstring). ``reference`` defaults to ``result.reference``."""
    if not isinstance(n_fronts, (int, np.integer)) or n_fronts < 2:
        raise ParameterError(f"front_uncertainty: n_fronts must be an integer >= 2, got {n_fronts!r}")
    if not isinstance(n_designs, (int, np.integer)) or n_designs < 1:
        raise ParameterError(f"front_uncertainty: n_designs must be an integer >= 1, got {n_designs!r}")
    reference = result.reference if reference is None else np.asarray(reference, dtype=float)
    if reference.shape != (2,) or not np.isfinite(reference).all():
        raise ParameterError(f"front_uncertainty: reference must be 2 finite numbers, got {reference}")
    rng = np.random.default_rng(seed)
    lower, upper = result.bounds.T
    designs = np.vstack([lower + (upper - lower) * qmc.LatinHypercube(d=lower.size, rng=rng).random(n_designs),
                         result.X])
    draws = np.stack([model.posterior_draws(designs, n_fronts, rng) for model in result.models], axis=-1)
    fronts = [draw[nondominated(draw)] for draw in draws]  # draws: (n_fronts, designs, 2)
    points = np.vstack(fronts)
    sets = np.repeat(np.arange(n_fronts), [f.shape[0] for f in fronts])
    vorob = moocore.vorob_t(points, sets, ref=reference)
    return FrontUncertainty(
        points=points, sets=sets, eaf=moocore.eaf(points, sets),
        vorob_threshold=float(vorob["threshold"]), vorob_expectation=np.asarray(vorob["ve"]),
        vorob_hypervolume=float(vorob["avg_hyp"]),
        vorob_deviation=float(moocore.vorob_dev(points, sets, ref=reference, ve=vorob["ve"])),
        reference=reference)
