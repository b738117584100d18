"""Monte Carlo Sobol indices for the surrogate benchmarks: the pick-freeze design and its estimators (a module of the
benchmark scripts, independent of spflow's own Sobol code -- :mod:`spflow.plugins.surrogates.sobol_sampling` uses
the same estimators -- so that the references and scores do not rest on the code being scored).

Two base samples A and B (n, d) and, for each input i, the matrix A_B^(i): A with its column i taken from B
(Saltelli et al. 2010, "Variance based sensitivity analysis of model output", Comput. Phys. Commun. 181, 259-270,
Section 3). From f at the n (d + 2) points:

* first order S_i = (1/n) Σ_j f(B)_j (f(A_B^(i))_j - f(A)_j) / V (Saltelli et al. 2010, Table 2 (b));
* total S_Ti = (1/2n) Σ_j (f(A)_j - f(A_B^(i))_j)^2 / V (Jansen 1999; Saltelli et al. 2010, Table 2 (f));

with V the variance of f over the 2n points of A and B. A and B are the two halves of a scrambled Sobol' sequence
in 2d dimensions (randomised quasi-Monte Carlo): for a fixed budget its error is well below plain Monte Carlo's on
smooth functions, and independent scramblings give independent replicates, whose spread is the standard error of
their mean (:func:`replicated_indices`).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from scipy.stats import qmc


class PickFreeze:
    """The n (d + 2) points [A; B; A_B^(1); ...; A_B^(d)] on the box [lower, upper] (uniform inputs), from the
    scrambled Sobol' sequence with ``seed``; ``n_base`` a power of 2."""

    def __init__(self, lower: np.ndarray, upper: np.ndarray, n_base: int, seed: int):
        d = lower.size
        u = qmc.Sobol(2 * d, scramble=True, seed=seed).random(n_base)
        a, b = lower + (upper - lower) * u[:, :d], lower + (upper - lower) * u[:, d:]
        mixed = np.repeat(a[None], d, axis=0)
        for i in range(d):
            mixed[i, :, i] = b[:, i]
        self.n_base, self.d = n_base, d
        self.points = np.concatenate([a, b, mixed.reshape(-1, d)])

    def indices(self, values: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(first order, total), each (m, d), from ``values`` (n (d + 2), m) of f at :attr:`points`; NaN for an
        output whose values do not vary."""
        n, d = self.n_base, self.d
        values = values.reshape(self.points.shape[0], -1)
        fa, fb = values[:n], values[n:2 * n]
        fab = values[2 * n:].reshape(d, n, -1)
        variance = np.var(values[:2 * n], axis=0)
        with np.errstate(divide="ignore", invalid="ignore"):
            first = np.mean(fb * (fab - fa), axis=1) / variance
            total = 0.5 * np.mean((fa - fab) ** 2, axis=1) / variance
        return first.T, total.T


def replicated_indices(func: Callable[[np.ndarray], np.ndarray], lower: np.ndarray, upper: np.ndarray,
                       n_base: int, replicates: int, seed: int) -> tuple[np.ndarray, np.ndarray, np.ndarray,
                                                                           np.ndarray]:
    """(first, total, SE of first, SE of total), each (m, d): the mean of the estimates of ``replicates`` independent
    scramblings (seeds ``seed``, ``seed + 1``, ...), and the standard error of that mean from their spread.
    ``func`` maps points (k, d) to values (k, m)."""
    estimates = []
    for r in range(replicates):
        design = PickFreeze(lower, upper, n_base, seed + r)
        estimates.append(design.indices(func(design.points)))
    first, total = (np.array(e) for e in zip(*estimates))  # (replicates, m, d)
    se = [a.std(axis=0, ddof=1) / np.sqrt(replicates) for a in (first, total)]
    return first.mean(axis=0), total.mean(axis=0), se[0], se[1]
