"""Buckley-Leverett displacement with the Welge tangent construction (thesis Eqs. 1.10-1.11; Buckley & Leverett 1942;
Welge 1952).

Injecting a higher saturation ``S_inj`` into ``S_init`` gives a shock from ``S_init`` to the Welge front saturation
``S_f`` (tangent from ``(S_init, f(S_init))``: ``f'(S_f) = [f(S_f) - f(S_init)]/(S_f - S_init)``) followed by a
rarefaction ``f'(S) = x_D/t_D`` up to ``S_inj``; if ``S_inj <= S_f`` a single shock. Breakthrough at
``t_D = 1/f'(S_f)``; after it the outlet saturation solves ``f'(S_2) = 1/t_D`` and Welge gives
``N_p = S_2 + t_D (1 - f(S_2)) - S_init`` -- all produced by :class:`oracles.wave_fan.WaveFan`.
"""

import math

import numpy as np
from scipy.optimize import brentq

from oracles.wave_fan import Segment, WaveFan

_GRID_POINTS = 4001


def welge_front_saturation(flux, s_init: float, s_max: float | None = None) -> float:
    """Shock saturation ``S_f`` maximising the chord slope ``[f(S) - f(S_init)]/(S - S_init)`` on ``(S_init, s_max]``.

    At an interior maximum the chord is tangent to ``f`` (Welge); a maximum at ``s_max`` means a single shock.
    """
    s_max = flux.s_max if s_max is None else s_max
    if not s_init < s_max:
        raise ValueError(f"s_init must be < s_max = {s_max}, got {s_init}")
    f_init = float(flux.fw(s_init))
    grid = np.linspace(s_init, s_max, _GRID_POINTS)[1:]
    chord = (flux.fw(grid) - f_init) / (grid - s_init)
    k = int(np.argmax(chord))
    if k == grid.size - 1:
        return float(s_max)

    def tangency(s):  # > 0 while the chord slope still rises, < 0 after its maximum
        return float(flux.dfw(s)) * (s - s_init) - (float(flux.fw(s)) - f_init)

    lo = grid[k - 1] if k > 0 else s_init + 1e-12 * (s_max - s_init)
    return brentq(tangency, lo, grid[k + 1], xtol=1e-14, rtol=1e-14)


def buckley_leverett(flux, s_init: float | None = None, s_inj: float | None = None) -> WaveFan:
    """Self-similar Buckley-Leverett solution for injecting ``s_inj`` (default ``1 - S_or``) into ``s_init``.

    ``s_init`` defaults to the connate saturation ``S_wc``; ``s_inj`` must exceed ``s_init``.
    """
    s_init = flux.s_min if s_init is None else float(s_init)
    s_inj = flux.s_max if s_inj is None else float(s_inj)
    if not flux.s_min <= s_init < s_inj <= flux.s_max:
        raise ValueError(
            f"need s_min = {flux.s_min} <= s_init < s_inj <= s_max = {flux.s_max}, got s_init={s_init}, s_inj={s_inj}"
        )
    s_front = welge_front_saturation(flux, s_init, s_inj)
    if s_front >= s_inj:
        speed = (float(flux.fw(s_inj)) - float(flux.fw(s_init))) / (s_inj - s_init)
        return WaveFan((Segment(0.0, speed, flux, s_inj, s_inj), Segment(speed, math.inf, flux, s_init, s_init)))
    front_speed = float(flux.dfw(s_front))
    inlet_speed = float(flux.dfw(s_inj))
    segments = []
    if inlet_speed > 0.0:
        segments.append(Segment(0.0, inlet_speed, flux, s_inj, s_inj))
    segments.append(Segment(inlet_speed, front_speed, flux, s_inj, s_front))
    segments.append(Segment(front_speed, math.inf, flux, s_init, s_init))
    return WaveFan(tuple(segments))
