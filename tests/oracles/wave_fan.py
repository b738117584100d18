"""Self-similar saturation profiles ``S(xi)``, ``xi = x_D/t_D``, of 1-D Riemann problems (fractional-flow theory).

A profile is a left-to-right list of segments covering ``0 <= xi < inf``: constant states and rarefaction fans on
which ``f'(S) = xi``; jumps between segments are shocks. Integrals of a fan are exact (no quadrature): along a
rarefaction ``d xi = f''(S) dS`` so ``int S d xi = [S f'(S) - f(S)]`` (the Welge identity). This gives the oil in
place, hence the cumulative oil ``N_p(t_D) = t_D int_0^{1/t_D} (S - S_init) d xi``, and the outlet state at
``xi = 1/t_D`` (Buckley & Leverett 1942; Pope 1980; Larson & Hirasaki 1978).
"""

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.optimize import brentq


def rarefaction_saturation(flux: Any, speed: float, s_a: float, s_b: float) -> float:
    """Saturation ``S`` in ``[s_a, s_b]`` (either order) with ``flux.dfw(S) = speed``.

    ``flux.dfw`` must be monotone on the interval (a rarefaction lies on a branch of one convexity). Speeds outside
    the range of ``dfw`` clamp to the nearer end point.
    """
    lo, hi = min(s_a, s_b), max(s_a, s_b)
    d_lo, d_hi = float(flux.dfw(lo)), float(flux.dfw(hi))
    if (speed - d_lo) * (speed - d_hi) >= 0.0:
        return lo if abs(speed - d_lo) <= abs(speed - d_hi) else hi
    return brentq(lambda s: float(flux.dfw(s)) - speed, lo, hi, xtol=1e-14, rtol=1e-14)


@dataclass(frozen=True)
class Segment:
    """One piece of a self-similar profile on ``xi_lo <= xi < xi_hi``.

    ``flux`` is the fractional-flow curve the state lies on (it gives the outlet water cut); ``s_lo``/``s_hi`` are
    the saturations at ``xi_lo``/``xi_hi``: equal for a constant state, different for a rarefaction (then
    ``flux.dfw(s_lo) = xi_lo`` and ``flux.dfw(s_hi) = xi_hi``).
    """

    xi_lo: float
    xi_hi: float
    flux: Any
    s_lo: float
    s_hi: float

    @property
    def is_constant(self) -> bool:
        return self.s_lo == self.s_hi

    def saturation(self, xi: float) -> float:
        if self.is_constant:
            return self.s_lo
        return rarefaction_saturation(self.flux, xi, self.s_lo, self.s_hi)

    def integral(self, xi_a: float, xi_b: float) -> float:
        """Exact ``int_{xi_a}^{xi_b} S d xi`` for ``xi_lo <= xi_a <= xi_b <= xi_hi``."""
        if xi_b <= xi_a:
            return 0.0
        if self.is_constant:
            return self.s_lo * (xi_b - xi_a)

        def welge(s):
            return s * float(self.flux.dfw(s)) - float(self.flux.fw(s))

        return welge(self.saturation(xi_b)) - welge(self.saturation(xi_a))


@dataclass(frozen=True)
class WaveFan:
    """A self-similar profile: contiguous segments from ``xi = 0`` to ``inf`` (the last one is the initial state)."""

    segments: tuple

    def __post_init__(self):
        if not self.segments or self.segments[0].xi_lo != 0.0 or not math.isinf(self.segments[-1].xi_hi):
            raise ValueError("segments must cover xi in [0, inf)")
        for left, right in zip(self.segments, self.segments[1:]):
            if left.xi_hi != right.xi_lo or left.xi_hi < left.xi_lo:
                raise ValueError(f"segments must be contiguous and ordered, got {left} then {right}")

    @property
    def s_init(self) -> float:
        """Initial (undisturbed, right-hand) saturation."""
        return self.segments[-1].s_lo

    def shock_speeds(self) -> list:
        """Speeds ``xi`` of the discontinuities, slowest first."""
        return [
            left.xi_hi
            for left, right in zip(self.segments, self.segments[1:])
            if abs(left.s_hi - right.s_lo) > 1e-12
        ]

    def _segment(self, xi: float) -> Segment:
        for segment in self.segments:
            if xi < segment.xi_hi:
                return segment
        return self.segments[-1]

    def saturation(self, xi):
        """``S(xi)`` for scalar or array ``xi >= 0``."""
        return np.vectorize(lambda v: self._segment(v).saturation(v), otypes=[float])(xi)

    def water_cut(self, xi):
        """Water fractional flow of the state at ``xi`` (at ``xi = 1/t_D`` this is the outlet water cut)."""

        def cut(v):
            segment = self._segment(v)
            return float(segment.flux.fw(segment.saturation(v)))

        return np.vectorize(cut, otypes=[float])(xi)

    def integral(self, xi_max: float) -> float:
        """Exact ``int_0^{xi_max} (S - S_init) d xi``."""
        total = 0.0
        for segment in self.segments:
            upper = min(segment.xi_hi, xi_max)
            total += segment.integral(segment.xi_lo, upper) - self.s_init * max(upper - segment.xi_lo, 0.0)
            if segment.xi_hi >= xi_max:
                break
        return total

    def profile(self, x_d, t_d: float):
        """Saturation ``S(x_D, t_D)`` at ``t_D > 0`` injected PV."""
        _check_time(t_d)
        return self.saturation(np.asarray(x_d, dtype=float) / t_d)

    def cell_averages(self, t_d: float, n_cells: int):
        """Exact averages of ``S(x_D, t_D)`` over ``n_cells`` equal cells of ``[0, 1]`` (from :meth:`integral`)."""
        _check_time(t_d)
        if n_cells < 1:
            raise ValueError(f"n_cells must be >= 1, got {n_cells}")
        edges = np.linspace(0.0, 1.0, n_cells + 1)
        cumulative = np.array([t_d * self.integral(x / t_d) for x in edges])
        return self.s_init + np.diff(cumulative) * n_cells

    def outlet_saturation(self, t_d):
        """Saturation at the outlet ``x_D = 1`` versus injected PV."""
        return np.vectorize(lambda t: float(self.saturation(1.0 / _check_time(t))), otypes=[float])(t_d)

    def oil_cut(self, t_d):
        """Outlet oil cut ``1 - f`` versus injected PV."""
        return np.vectorize(lambda t: 1.0 - float(self.water_cut(1.0 / _check_time(t))), otypes=[float])(t_d)

    def cumulative_oil(self, t_d):
        """Cumulative oil produced in PV, ``N_p(t_D) = int_0^1 (S - S_init) dx_D`` (water volume balance)."""
        return np.vectorize(lambda t: _check_time(t) * self.integral(1.0 / t), otypes=[float])(t_d)


def _check_time(t_d: float) -> float:
    if not t_d > 0.0:
        raise ValueError(f"t_d (injected PV) must be > 0, got {t_d}")
    return float(t_d)
