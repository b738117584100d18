"""Pressure-transducer model: sampling on a fixed PV interval, relative AR(1) noise, zero offset and drift.

A differential transducer's error is dominated by slow processes (temperature, flow pulsation filtered by the
lines), so successive samples are correlated; we model the relative error as a stationary first-order
autoregressive sequence

    e_0 ~ N(0, s^2),   e_k = r e_{k-1} + s sqrt(1 - r^2) w_k,   w_k ~ N(0, 1) i.i.d.,

which has mean 0, variance s^2 and lag-k autocorrelation r^k. The reading at injected volume ``pv_k`` is

    dp_meas(pv_k) = dp(pv_k) (1 + e_k) + offset + drift * pv_k          (Pa).
"""

from __future__ import annotations

import math

import numpy as np

from .noise_model import NoiseModel

__all__ = ["ar1_noise", "sample_times", "read_pressure"]


def ar1_noise(n: int, sigma: float, rho: float, rng: np.random.Generator) -> np.ndarray:
    """``n`` samples of the stationary AR(1) sequence above (standard deviation ``sigma``, lag-1 correlation
    ``rho`` in [0, 1)). Draws exactly ``n`` standard normals from ``rng``."""
    if not 0.0 <= rho < 1.0:
        raise ValueError(f"AR(1) correlation rho = {rho!r} is out of range; allowed [0, 1)")
    if sigma < 0.0:
        raise ValueError(f"AR(1) standard deviation sigma = {sigma!r} is out of range; allowed [0, inf)")
    w = rng.standard_normal(n)
    e = np.empty(n)
    if n == 0:
        return e
    innovation = sigma * math.sqrt(1.0 - rho * rho)
    e[0] = sigma * w[0]
    for k in range(1, n):
        e[k] = rho * e[k - 1] + innovation * w[k]
    return e


def sample_times(total_pv: float, interval_pv: float) -> np.ndarray:
    """Transducer sample points ``0, interval, 2 interval, ...`` up to ``total_pv`` (PV)."""
    n = int(math.floor(total_pv / interval_pv + 1.0e-9))
    return np.minimum(np.arange(n + 1, dtype=np.float64) * interval_pv, total_pv)  # no round-off past the end


def read_pressure(pv: np.ndarray, dp: np.ndarray, noise: NoiseModel, rng: np.random.Generator):
    """Transducer readings of the point signal ``dp(pv)`` (Pa, linearly interpolated between ``pv`` points).

    Returns ``(pv_samples, dp_measured)`` in PV and Pa.
    """
    times = sample_times(float(pv[-1]), noise.pressure_interval_pv)
    true = np.interp(times, pv, dp)
    e = ar1_noise(times.size, noise.pressure_relative, noise.pressure_ar1, rng)
    return times, true * (1.0 + e) + noise.pressure_offset_pa + noise.pressure_drift_pa_per_pv * times
