"""Analytic test functions of the surrogate benchmarks, each with the box of its uniform inputs: Ishigami (a = 7,
b = 0.1 on [-π, π]^3), the Sobol G-function (d = 8, a = (0, 1, 4.5, 9, 99, 99, 99, 99) on [0, 1]^8) and Borehole
(8 inputs rw, r, Tu, Hu, Tl, Hl, L, Kw on the box of Surjanovic & Bingham's library). A module of the benchmark
scripts (imported by its siblings), not of spflow.
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
