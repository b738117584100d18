"""Noise-consistent ranges of the NSGA-II history match: a likelihood-ratio confidence region under the lab's
measurement-error model, built from every design the GA evaluated.

The calibrated ranges of Fig. 3.14 (min/max of the final Pareto set) are not uncertainty intervals: the
non-dominated set of the unweighted misfits of Eqs. 3.16-3.17 fits the training coreflood's noise and collapses onto
a narrow region around the noise-shifted optimum (docs/calibration.md). This module adds the ranges the measurement
noise allows:

* **Error model.** Each training block (variable, experiment) gets the error model of the lab's measurement chain,
  :func:`~spflow.plugins.gap.error_model.block_error_model` (AR(1) relative transducer noise for dp, a random walk
  of tube readings for recovery, white tube readings for oil cut), at the block's finite observations on the
  simulator grid. The measurement model is the coreflood's ``noise_*`` attrs, carried by the ``observations`` stage
  (:func:`~spflow.plugins.gap.observed.observed_experiment`); a file without them gets the default
  :class:`~spflow.synthetic.NoiseModel` and ``noise_from_data`` is false. Oil cut and recovery are the same tube
  readings, so when both are objectives of one experiment only recovery enters the statistic.
* **Statistic.** χ²(ξ) = Σ_blocks Σ_t w_t(ξ)², w = the whitened residuals of P(ξ) − y, P the surrogate's mean: the
  Gaussian misfit e'Σ⁻¹e, i.e. −2 log L(ξ) up to a constant (Eq. 3.16's ½‖P − y‖² with the noise covariance as
  the metric).
* **Region** (Wilks' likelihood ratio): {ξ in the box: χ²(ξ) − χ²_min <= χ²_p(level)}, p the number of parameters.
  For a linear model with Gaussian noise it covers the truth with probability ``level`` exactly; its projections on
  the parameter axes hold the truth simultaneously with probability >= ``level``.
* **Computed, not sampled** (:func:`region_extent`): the GA archive clusters near the front of the *unweighted*
  objectives, which is not where χ² is smallest, so min/max over archive points inside the region falls short of
  the region's extent (measured on the clean twin: the archive's lowest χ² lay 9-20 above the true minimum). The
  minimum is therefore polished from the best archive points (L-BFGS-B), and each parameter's lower and upper end is
  the solution of ``min ±ξ_i subject to χ²(ξ) <= χ²_min + χ²_p(level)`` (SLSQP from the minimum), merged with the
  archive points inside the region. Gradients are forward differences computed in one batched surrogate call.

Assumptions: the surrogate error is not included (P is the mean; a surrogate off by more than the noise shifts the
region); the measurement model is right; a region that is not star-shaped around the minimum may extend beyond
the local solutions of the constrained problems (the archive points inside the region are kept for that reason).
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import dataclass

import numpy as np
import xarray as xr

from spflow.core.errors import ParameterError
from spflow.plugins.calibration.aligned_data import AlignedData
from spflow.plugins.calibration.nsga2_misfits import residuals
from spflow.plugins.gap.error_model import BlockErrorModel, block_error_model
from spflow.plugins.gap.observed import observed_experiment

__all__ = ["ConfidenceRegion", "NoiseMisfit", "region_extent", "whitened_chi2", "check_level"]

#: Archive points per surrogate call when χ² is evaluated (bounds the memory of the prediction matrix).
_BATCH = 10_000


def check_level(level: float) -> float:
    """``level`` as a float in the open interval (0, 1); otherwise a ParameterError naming the field."""
    if not 0.0 < level < 1.0:
        raise ParameterError(f"confidence_level = {level!r} is out of range; allowed (0, 1) (open)")
    return float(level)


def whitened_chi2(block_residuals: Iterable[np.ndarray], models: Iterable[BlockErrorModel]) -> np.ndarray:
    """χ² = Σ_blocks Σ_t w_t² of residual matrices (n_points, n_block) under their block error models: (n_points,)."""
    total = 0.0
    for r, model in zip(block_residuals, models, strict=True):
        total = total + np.sum(model.whiten(np.atleast_2d(r).T) ** 2, axis=0)
    return np.asarray(total)


@dataclass(frozen=True)
class ConfidenceRegion:
    """Per-parameter extent (``lower``, ``upper``) of a likelihood-ratio region; ``count`` archive points lie in it;
    ``best`` is the point of the minimum ``chi2_min`` (the polished minimum, or an archive point that is lower)."""

    lower: np.ndarray
    upper: np.ndarray
    count: int
    level: float
    threshold: float
    chi2_min: float
    best: np.ndarray


#: Forward-difference step of the gradients, in units of the box width.
_STEP = 1e-6
#: Archive points the minimum is polished from.
_STARTS = 5
#: Accepted constraint violation of a computed end, as a fraction of the threshold (moves the end by ~1e-5).
_SLACK = 1e-4


def _gradient(chi2: Callable[[np.ndarray], np.ndarray], u: np.ndarray, to_x) -> tuple[float, np.ndarray]:
    """χ² and its forward-difference gradient in unit-box coordinates ``u`` from one batched call."""
    steps = np.where(u + _STEP > 1.0, -_STEP, _STEP)  # backward at the upper face of the box
    values = chi2(to_x(np.vstack([u, u + np.diag(steps)])))
    return float(values[0]), (values[1:] - values[0]) / steps


def region_extent(chi2: Callable[[np.ndarray], np.ndarray], lower: np.ndarray, upper: np.ndarray,
                  archive: np.ndarray, level: float) -> ConfidenceRegion:
    """Extent of {x in [lower, upper]: χ²(x) − χ²_min <= χ²_p(level)} (module docstring); ``chi2(points)`` maps
    (n, p) points to (n,) values, ``archive`` (n, p) holds evaluated points (the starts and a lower bound of the
    extent)."""
    from scipy.optimize import minimize

    lower, upper = np.asarray(lower, dtype=float), np.asarray(upper, dtype=float)
    archive = np.atleast_2d(archive)
    level = check_level(level)
    values = np.asarray(chi2(archive), dtype=float)
    if len(values) != len(archive) or not np.all(np.isfinite(values)):
        raise ParameterError(f"likelihood-ratio region: need one finite chi2 per archive point, got {len(values)} "
                             f"values for {len(archive)} points")
    width = upper - lower
    to_x = lambda u: lower + np.clip(u, 0.0, 1.0) * width  # noqa: E731
    last: dict = {}

    def grad(u):
        """``_gradient`` at ``u``, remembered for the next call: SLSQP asks for the constraint's value and its
        Jacobian at the same point one after the other."""
        key = u.tobytes()
        if key not in last:
            last.clear()
            last[key] = _gradient(chi2, u, to_x)
        return last[key]

    box = [(0.0, 1.0)] * len(lower)
    best_u, best = None, np.inf
    for k in np.argsort(values)[:_STARTS]:
        res = minimize(grad, (archive[k] - lower) / width, jac=True, method="L-BFGS-B", bounds=box)
        if res.fun < best:
            best_u, best = np.clip(res.x, 0.0, 1.0), float(res.fun)
    chi2_min = min(best, float(values.min()))
    best_x = to_x(best_u) if best <= values.min() else archive[int(np.argmin(values))]
    from scipy import stats

    threshold = float(stats.chi2.ppf(level, df=len(lower)))
    limit = chi2_min + threshold
    inside = (archive - lower) / width
    inside = np.vstack([inside[values <= limit], best_u])
    ends = [inside]
    constraint = {"type": "ineq", "fun": lambda u: limit - grad(u)[0], "jac": lambda u: -grad(u)[1]}
    for i in range(len(lower)):
        for sign in (1.0, -1.0):
            e = np.zeros(len(lower))
            e[i] = sign
            res = minimize(lambda u: (e @ u, e), best_u, jac=True, method="SLSQP", bounds=box,
                           constraints=[constraint])
            u = np.clip(res.x, 0.0, 1.0)
            if chi2(to_x(u[None, :]))[0] <= limit + _SLACK * threshold:  # SLSQP meets the constraint to ~1e-7
                ends.append(u[None, :])
    ends = to_x(np.vstack(ends))
    return ConfidenceRegion(ends.min(axis=0), ends.max(axis=0), int(np.sum(values <= limit)), level, threshold,
                            chi2_min, best_x)


class NoiseMisfit:
    """χ²(ξ) of the training blocks ``pairs`` (variable, experiment) of ``aligned`` under the measurement model the
    ``observations`` carry (module docstring). The aligned points of each block must be the experiment's measured
    grid points: the AR(1) and random-walk recursions run over consecutive grid points."""

    def __init__(self, observations: xr.Dataset, aligned: AlignedData, pairs: list[tuple[str, str]]):
        self.pairs = [(v, e) for v, e in pairs if not (v == "oil_cut" and ("recovery", e) in pairs)]
        experiments = {e: observed_experiment(observations, e) for e in dict.fromkeys(e for _, e in self.pairs)}
        self.aligned = aligned
        self.models = []
        for variable, experiment in self.pairs:
            exp, pv = experiments[experiment], aligned.blocks[(variable, experiment)][2]
            measured = exp.pv[np.isfinite(exp.observed[variable])]
            if pv.size != measured.size or not np.allclose(pv, measured, rtol=0.0, atol=1e-9):
                raise ParameterError(f"noise-consistent ranges: the predicted PV points of {variable!r} in "
                                     f"{experiment!r} are not the {measured.size} measured points of the "
                                     f"observations' {exp.pv_step:g} PV grid; build the surrogate's responses on "
                                     "the observations' pv_step")
            self.models.append(block_error_model(variable, exp, aligned.observed(variable, experiment)))
        self.noise_from_data = all(experiments[e].noise_from_data for e in experiments)
        self.n_data = int(sum(m.scale.size for m in self.models))

    def chi2(self, prediction: np.ndarray) -> np.ndarray:
        """χ² of predictions (n_points, n_output) labelled like ``aligned``: (n_points,)."""
        return whitened_chi2((r for r, _ in residuals(prediction, self.aligned, self.pairs)), self.models)

    def region(self, predict: Callable[[np.ndarray], np.ndarray], lower: np.ndarray, upper: np.ndarray,
               archive: np.ndarray, level: float) -> ConfidenceRegion:
        """The likelihood-ratio region in the box [lower, upper] (:func:`region_extent`), started from the
        ``archive`` points (n, n_param); ``predict(x)`` gives P(x)."""
        def chi2(points):
            return np.concatenate([self.chi2(predict(points[i: i + _BATCH])) for i in range(0, len(points), _BATCH)])

        return region_extent(chi2, lower, upper, archive, level)
