"""Analytic test functions of the surrogate benchmarks, each with the box of its uniform inputs: Ishigami (a = 7,
b = 0.1 on [-π, π]^3), the Sobol G-function (d = 8, a = (0, 1, 4.5, 9, 99, 99, 99, 99) on [0, 1]^8) and Borehole
(8 inputs rw, r, Tu, Hu, Tl, Hl, L, Kw on the box of Surjanovic & Bingham's library), and the closed-form Sobol
indices of the first two (``CLOSED_FORM_SOBOL``; checked against Monte Carlo in
tests/surrogates/test_benchmark_sobol_references.py). A module of the benchmark scripts (imported by its siblings),
not of spflow.
"""

from __future__ import annotations

import numpy as np


def ishigami(x: np.ndarray) -> np.ndarray:
    return np.sin(x[:, 0]) + 7.0 * np.sin(x[:, 1]) ** 2 + 0.1 * x[:, 2] ** 4 * np.sin(x[:, 0])


G_A = np.array([0.0, 1.0, 4.5, 9.0, 99.0, 99.0, 99.0, 99.0])


def g_function(x: np.ndarray) -> np.ndarray:
    return np.prod((np.abs(4.0 * x - 2.0) + G_A) / (1.0 + G_A), axis=1)


def borehole(x: np.ndarray) -> np.ndarray:
    rw, r, tu, hu, tl, hl, length, kw = x.T
    log_ratio = np.log(r / rw)
    return 2.0 * np.pi * tu * (hu - hl) / (log_ratio * (1.0 + 2.0 * length * tu / (log_ratio * rw**2 * kw) + tu / tl))


#: name -> (function, lower, upper) of the uniform input box.
PROBLEMS = {
    "ishigami": (ishigami, np.full(3, -np.pi), np.full(3, np.pi)),
    "g_function": (g_function, np.zeros(8), np.ones(8)),
    "borehole": (borehole, np.array([0.05, 100.0, 63070.0, 990.0, 63.1, 700.0, 1120.0, 9855.0]),
                 np.array([0.15, 50000.0, 115600.0, 1110.0, 116.0, 820.0, 1680.0, 12045.0])),
}


def ishigami_sobol(a: float = 7.0, b: float = 0.1) -> tuple[np.ndarray, np.ndarray]:
    """Closed-form (first-order, total) Sobol indices of the Ishigami function on U(-π, π)^3 (Ishigami & Homma 1990;
    Sobol' & Levitan 1999): partial variances V1 = (1 + b π^4/5)^2 / 2, V2 = a^2/8, V3 = 0, V13 = b^2 π^8 (1/18 -
    1/50), all other interactions zero."""
    v1 = 0.5 * (1.0 + b * np.pi**4 / 5.0) ** 2
    v2 = a**2 / 8.0
    v13 = b**2 * np.pi**8 * (1.0 / 18.0 - 1.0 / 50.0)
    variance = v1 + v2 + v13
    return np.array([v1, v2, 0.0]) / variance, np.array([v1 + v13, v2, v13]) / variance


def g_function_sobol(a: np.ndarray = G_A) -> tuple[np.ndarray, np.ndarray]:
    """Closed-form (first-order, total) Sobol indices of the G-function on U(0, 1)^d (Sobol' 1990; Saltelli et al.
    2010): V_i = 1 / (3 (1 + a_i)^2), V = Π (1 + V_i) - 1, S_i = V_i / V, S_Ti = V_i Π_{j≠i} (1 + V_j) / V."""
    v = 1.0 / (3.0 * (1.0 + np.asarray(a, dtype=float)) ** 2)
    variance = np.prod(1.0 + v) - 1.0
    return v / variance, v * np.prod(1.0 + v) / (1.0 + v) / variance


#: name -> (first-order, total) indices in closed form, for the problems that have one (Borehole has none).
CLOSED_FORM_SOBOL = {"ishigami": ishigami_sobol, "g_function": g_function_sobol}
