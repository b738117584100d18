"""The error model of a gap diagnosis: AR(1) errors per QoI block, fixed from the lab's measurement model.

Every candidate model is scored under the *same* error model (docs/gap.md, Method: **Error
model**; an AR(1) likelihood as in Schoups & Vrugt 2010): misfit differences
between candidates are then comparable, and autocorrelated transducer noise does not inflate them. One block is
one (variable, experiment) series on the simulator grid. Within a block the error is

    e_t = a_t eps_t,   eps_0 ~ N(0, 1),   eps_t = phi eps_{t-1} + sqrt(1 - phi^2) w_t,   w_t ~ N(0, 1) iid

(stationary AR(1) of scale ``a_t``; ``phi = 0`` is white noise), or, for cumulative quantities (``phi = 1``), the
random walk ``e_t = e_{t-1} + a_t w_t`` (``e_{-1} = 0``). Whitening inverts these recursions exactly, so the
whitened residuals ``w`` are iid N(0, 1) when the model is right, and ``sum w^2`` is the Gaussian misfit
``e' Sigma^-1 e`` (the AR(1) likelihood of Schoups & Vrugt 2010 with known parameters).

Scales and correlations come from the measurement model (:class:`spflow.synthetic.NoiseModel`, ``docs/data.md``),
never from the residuals of any fit (that would let the model error pass as noise):

* ``dp`` — relative transducer noise: ``a_t = pressure_relative |dp_obs,t|`` (floored at 5 % of the block's
  largest reading), ``phi = pressure_ar1 ** (pv_step / pressure_interval_pv)``;
* ``oil_cut`` — tube-reading error, uniform on +-resolution/2: ``a = oil_resolution_ml / sqrt(12) /
  (tube_pv PV_ml)``, white; divided by ``sqrt(pv_step / tube_pv)`` when a grid interval averages several tubes;
* ``recovery`` — the cumulative sum of the same readings / OOIP: a random walk with steps of
  ``oil_resolution_ml / sqrt(12) / OOIP_ml * sqrt(pv_step / tube_pv)``. (Its whitened residual is the oil-cut
  residual again: use one of the two in a likelihood, not both.)
* effluent assays — relative error ``concentration_relative |c_obs|``, white, floored at 5 % of the block maximum
  or of the largest injected concentration of the species, whichever is larger. The injected floor is the assay's
  working range: without it a held-out coreflood whose effluent stays near zero (e.g. polymer held back by
  adsorption) would get a noise scale of round-off size and whitened residuals of 1e12.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from spflow.core.errors import ParameterError
from spflow.plugins.forward.parameters import resolve_params
from spflow.synthetic.core_volumes import ooip_ml, pore_volume_ml

__all__ = ["BlockErrorModel", "block_error_model"]

_FLOOR = 0.05
# effluent assay -> the schedule field (ppm) of the injected concentration that sets its floor
_INJECTED = {"c_polymer_out": "polymer_ppm", "c_surfactant_out": "surfactant_ppm", "salinity_out": "salinity_ppm"}


@dataclass(frozen=True)
class BlockErrorModel:
    """AR(1) error of one block: scales ``scale`` (n,) in the variable's units and correlation ``phi`` in [0, 1]."""

    scale: np.ndarray
    phi: float

    def __post_init__(self):
        if not 0.0 <= self.phi <= 1.0:
            raise ParameterError(f"AR(1) correlation phi = {self.phi!r} is out of range; allowed [0, 1]")
        if not np.all(np.isfinite(self.scale)) or np.any(self.scale <= 0.0):
            raise ParameterError("AR(1) scales must be finite and > 0 (a noise level of 0 cannot weight a misfit; "
                                 "give the data's measurement model)")

    @property
    def integrated(self) -> bool:
        return self.phi == 1.0

    def whiten(self, e: np.ndarray) -> np.ndarray:
        """Whitened residuals of ``e`` (points on axis 0; extra axes, e.g. Jacobian columns, are carried along)."""
        e = np.asarray(e, dtype=float)
        a = self.scale.reshape((-1,) + (1,) * (e.ndim - 1))
        w = np.empty_like(e)
        if self.integrated:
            w[0] = e[0] / a[0]
            w[1:] = (e[1:] - e[:-1]) / a[1:]
            return w
        eps = e / a
        w[0] = eps[0]
        w[1:] = (eps[1:] - self.phi * eps[:-1]) / math.sqrt(1.0 - self.phi**2)
        return w

    def log_determinant(self) -> float:
        """``log det Sigma`` of the block's error covariance: ``sum 2 log a_t`` plus ``(n - 1) log(1 - phi^2)``
        for a stationary AR(1) (the whitening recursion is triangular with diagonal ``1 / a_0`` and
        ``1 / (a_t sqrt(1 - phi^2))``), ``sum 2 log a_t`` for a random walk (diagonal ``1 / a_t``)."""
        n = self.scale.size
        stationary = 0.0 if self.integrated or n < 2 else (n - 1) * math.log1p(-self.phi**2)
        return float(2.0 * np.sum(np.log(self.scale)) + stationary)

    def marginal_std(self) -> np.ndarray:
        """Standard deviation of each error ``e_t``."""
        return np.sqrt(np.cumsum(self.scale**2)) if self.integrated else self.scale.copy()

    def draw(self, rng: np.random.Generator, size: int) -> np.ndarray:
        """``size`` error realisations, shape (size, n)."""
        w = rng.standard_normal((size, self.scale.size))
        if self.integrated:
            return np.cumsum(w * self.scale, axis=1)
        eps = np.empty_like(w)
        eps[:, 0] = w[:, 0]
        innovation = math.sqrt(1.0 - self.phi**2)
        for t in range(1, self.scale.size):
            eps[:, t] = self.phi * eps[:, t - 1] + innovation * w[:, t]
        return eps * self.scale


def _relative(observed: np.ndarray, relative: float, reference: float = 0.0) -> np.ndarray:
    level = np.abs(observed)
    return relative * np.maximum(level, _FLOOR * max(level.max(), reference))


def uninformative(variable: str, experiment, observed: np.ndarray) -> bool:
    """Whether ``observed`` is an effluent assay of a species ``experiment`` never injects that reads zero
    throughout (e.g. surfactant in a polymer flood): it has no noise scale and carries no information, so a layout
    leaves it out."""
    if variable not in _INJECTED:
        return False
    injected = max(getattr(slug, _INJECTED[variable]) for slug in experiment.schedule.slugs)
    return injected == 0.0 and not np.any(observed)


def block_error_model(variable: str, experiment, observed: np.ndarray) -> BlockErrorModel:
    """The error model of ``variable`` of ``experiment`` (an :class:`~spflow.plugins.gap.observed.Experiment`)
    at its finite observations ``observed`` (module docstring)."""
    noise, step = experiment.measurement, experiment.pv_step
    n = observed.size
    core = resolve_params(experiment.core)
    pv_ml = experiment.pore_volume_ml or pore_volume_ml(core)
    tubes_per_step = max(1.0, step / noise.tube_pv)
    reading = noise.oil_resolution_ml / math.sqrt(12.0)
    if variable == "dp":
        phi = noise.pressure_ar1 ** (step / noise.pressure_interval_pv)
        return BlockErrorModel(_relative(observed, noise.pressure_relative), float(phi))
    if variable == "oil_cut":
        return BlockErrorModel(np.full(n, reading / (noise.tube_pv * pv_ml) / math.sqrt(tubes_per_step)), 0.0)
    if variable == "recovery":
        oil_ml = experiment.ooip_ml or ooip_ml(core)
        return BlockErrorModel(np.full(n, reading / oil_ml * math.sqrt(tubes_per_step)), 1.0)
    if variable in _INJECTED:
        injected = max(getattr(slug, _INJECTED[variable]) for slug in experiment.schedule.slugs)
        return BlockErrorModel(_relative(observed, noise.concentration_relative, injected)
                               / math.sqrt(tubes_per_step), 0.0)
    raise ParameterError(f"no error model for variable {variable!r}; allowed dp, oil_cut, recovery, c_polymer_out, "
                         "c_surfactant_out, salinity_out")
