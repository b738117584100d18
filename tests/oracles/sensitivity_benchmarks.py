"""Benchmark functions with analytic means, variances and Sobol indices (Ishigami; Sobol G-function).

Independent of spflow: closed forms from Ishigami & Homma (1990) and Saltelli & Sobol' (1995).
"""

from __future__ import annotations

import numpy as np

ISHIGAMI_BOUNDS = (-np.pi, np.pi)
G_STANDARD_A = np.array([0.0, 1.0, 4.5, 9.0, 99.0, 99.0, 99.0, 99.0])


def ishigami(x: np.ndarray, a: float = 7.0, b: float = 0.1) -> np.ndarray:
    """f(x) = sin x1 + a sin^2 x2 + b x3^4 sin x1 on [-pi, pi]^3."""
    return np.sin(x[:, 0]) + a * np.sin(x[:, 1]) ** 2 + b * x[:, 2] ** 4 * np.sin(x[:, 0])


def ishigami_moments(a: float = 7.0, b: float = 0.1) -> dict:
    """Mean, variance, first-order S, total ST and the S13 interaction of the Ishigami function."""
    pi4, pi8 = np.pi**4, np.pi**8
    d1 = b * pi4 / 5 + b**2 * pi8 / 50 + 0.5
    d2 = a**2 / 8
    d13 = b**2 * pi8 * (1 / 18 - 1 / 50)
    var = d1 + d2 + d13
    return {"mean": a / 2, "variance": var, "S": np.array([d1, d2, 0.0]) / var,
            "ST": np.array([d1 + d13, d2, d13]) / var, "S13": d13 / var}


def sobol_g(x: np.ndarray, a: np.ndarray = G_STANDARD_A) -> np.ndarray:
    """g(x) = prod_i (|4 x_i - 2| + a_i) / (1 + a_i) on [0, 1]^d."""
    return np.prod((np.abs(4 * x - 2) + a) / (1 + a), axis=1)


def sobol_g_moments(a: np.ndarray = G_STANDARD_A) -> dict:
    """Mean (1), variance, first-order and total Sobol indices of the G-function."""
    v = 1.0 / (3.0 * (1.0 + a) ** 2)
    var = np.prod(1 + v) - 1
    total = np.array([v[i] * np.prod(np.delete(1 + v, i)) for i in range(a.size)]) / var
    return {"mean": 1.0, "variance": var, "S": v / var, "ST": total}
