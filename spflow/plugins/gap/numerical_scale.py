"""How large the simulator's numerical error is in the data: a scale of the numerical-error term, estimated from
the calibration residuals (issue 20; docs/gap.md, Method: **Numerical error — the scale**).

:mod:`~spflow.plugins.gap.numerical_error` gives the *shape* of the base model's own numerical error, the spread
``d_i`` over other equally legitimate numerics. How much of it is in the data depends on who made the data: twins
made with the model's own numerics share its discretisation error exactly (there is none to absorb), a coreflood or
another simulator's data differ from it by about ``d`` or more. The error model of every block therefore takes the
scales ``c_i(s) = sqrt(a_i^2 + s^2 d_i^2)`` (``a`` the measurement model's; for a random-walk block the increments
of ``d``, as in :func:`~spflow.plugins.gap.numerical_error.inflate`), with one factor ``s`` in ``[0, s_max]``
estimated by maximum likelihood from the calibrated *base* model's calibration residuals -- a variance-component
estimate, profiled once under the base hypothesis and then used for every model, so all candidates are still judged
with one covariance.

The likelihood counts the calibrated parameters as REML does (Patterson & Thompson 1971): linearised at the base
fit, the residuals are ``r = J delta + e`` with ``delta ~ N(0, tau^2 I)`` the unit-box parameter shift (the
package's Laplace prior, scale ``tau``) and ``e ~ N(0, Sigma_s)``, so with ``w = W_s r`` and ``J_s = W_s J``
(``W_s`` the whitening of ``Sigma_s``) the log marginal likelihood is

    l(s) = -1/2 [ w'w - w'J_s (J_s'J_s + I/tau^2)^-1 J_s'w + log det(I + tau^2 J_s'J_s) + log det Sigma_s
                  + n log 2 pi ]

(Woodbury and the matrix determinant lemma applied to ``N(0, Sigma_s + tau^2 J J')``). The parameter part makes
the estimate see the residuals the recalibration under ``Sigma_s`` would leave, not those of the fit under
``Sigma_0``. The interval is the profile-likelihood set ``{s : 2 (l(s_hat) - l(s)) <= chi^2_1(level)}`` cut to
``[0, s_max]``. At the boundary ``s = 0`` the likelihood-ratio statistic is a 50:50 mixture of ``chi^2_0`` and
``chi^2_1`` (Self & Liang 1987), so the interval is conservative there (its level is ``(1 + level) / 2`` one-sided).
The estimate is made under the base hypothesis, so a physical gap located where the numerics are sensitive (a
moved polymer or oil front) raises it too. ``s_max`` (the diagnosis's default 1: the spread itself, which is
already the largest difference of two grid/scheme variants) caps that: the data may show less numerical error
than the worst case of the variants, never more -- a larger smearing than those variants produce is not the base
model's numerical error on its grid (docs/gap.md, Validation, where on twins only physical gaps pushed the
estimate above 1 and data from other numerics gave 0.4-0.5).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq, minimize_scalar
from scipy.stats import chi2

from spflow.core.errors import ParameterError

from .layout import Layout
from .numerical_error import inflate

__all__ = ["NumericalScale", "scale_log_likelihood", "estimate_scale"]


@dataclass(frozen=True)
class NumericalScale:
    """The estimated scale ``estimate`` of the numerical-error term, its profile-likelihood interval
    [``lower``, ``upper``] at ``level``, the cap ``maximum``, and the profile: ``grid`` and
    ``profile`` = ``l(grid) - l(estimate)`` (<= 0, nat)."""

    estimate: float
    lower: float
    upper: float
    maximum: float
    level: float
    grid: np.ndarray
    profile: np.ndarray

    def as_dict(self) -> dict:
        return {"estimate": self.estimate, "lower": self.lower, "upper": self.upper, "maximum": self.maximum,
                "level": self.level, "grid": [float(x) for x in self.grid],
                "profile_nat": [float(x) for x in self.profile]}

    def label(self) -> str:
        return (f"s = {self.estimate:.3g} ({100 * self.level:.0f} % interval {self.lower:.3g}-{self.upper:.3g}, "
                f"cap {self.maximum:g})")


def scale_log_likelihood(layout: Layout, spread: Mapping[tuple[str, str], np.ndarray], residual: np.ndarray,
                         jacobian: np.ndarray, tau: float, s: float) -> float:
    """``l(s)`` of the module docstring: raw residuals ``residual`` (model - data) and raw Jacobian ``jacobian``
    (w.r.t. the unit-box coordinates) of ``layout``'s points, the numerical spread ``spread`` scaled by ``s``."""
    inflated = inflate(layout, spread, s)
    w = inflated.whiten(np.asarray(residual, float))
    js = inflated.whiten(np.asarray(jacobian, float))
    q = js.shape[1]
    gram = js.T @ js
    precision = gram + np.eye(q) / tau**2
    g = js.T @ w
    quadratic = float(w @ w - g @ np.linalg.solve(precision, g))
    log_det_params = float(np.linalg.slogdet(np.eye(q) + tau**2 * gram)[1])
    return -0.5 * (quadratic + log_det_params + inflated.log_determinant() + w.size * np.log(2.0 * np.pi))


def estimate_scale(layout: Layout, spread: Mapping[tuple[str, str], np.ndarray], residual: np.ndarray,
                   jacobian: np.ndarray, tau: float, maximum: float = 1.0, level: float = 0.95,
                   points: int = 41) -> NumericalScale:
    """Maximum-likelihood scale of the numerical-error term on ``[0, maximum]`` (module docstring): the best of a
    ``points`` grid refined by a bounded scalar search, and its profile-likelihood interval at ``level``."""
    if not 0.0 <= maximum < np.inf:
        raise ParameterError(f"numerical_scale_max = {maximum!r} is out of range; allowed a finite number >= 0")
    if not 0.0 < level < 1.0:
        raise ParameterError(f"level = {level!r} is out of range; allowed (0, 1)")
    residual, jacobian = np.asarray(residual, float), np.asarray(jacobian, float)
    if residual.shape != (layout.size,) or jacobian.shape[0] != layout.size or not np.all(np.isfinite(residual)):
        raise ParameterError(f"the numerical-error scale needs finite residuals and a Jacobian on the layout's "
                             f"{layout.size} points (got {residual.shape} and {jacobian.shape})")

    def ll(s: float) -> float:
        return scale_log_likelihood(layout, spread, residual, jacobian, tau, s)

    grid = np.linspace(0.0, maximum, points) if maximum > 0.0 else np.zeros(1)
    values = np.array([ll(s) for s in grid])
    k = int(np.argmax(values))
    best, best_ll = float(grid[k]), float(values[k])
    if grid.size > 1:
        lo, hi = grid[max(k - 1, 0)], grid[min(k + 1, grid.size - 1)]
        res = minimize_scalar(lambda s: -ll(s), bounds=(lo, hi), method="bounded",
                              options={"xatol": 1e-4 * maximum})
        if -res.fun > best_ll:
            best, best_ll = float(res.x), float(-res.fun)
    drop = 0.5 * float(chi2.ppf(level, 1))

    def excess(s: float) -> float:
        return best_ll - ll(s) - drop

    lower = 0.0
    below = grid[grid < best]
    if below.size and excess(0.0) > 0.0:
        left = below[np.array([excess(s) > 0.0 for s in below])].max()
        lower = float(brentq(excess, left, best, xtol=1e-6 * max(maximum, 1.0)))
    upper = maximum
    above = grid[grid > best]
    if above.size and excess(maximum) > 0.0:
        right = above[np.array([excess(s) > 0.0 for s in above])].min()
        upper = float(brentq(excess, best, right, xtol=1e-6 * max(maximum, 1.0)))
    return NumericalScale(best, lower, upper, float(maximum), float(level), grid, values - best_ll)
