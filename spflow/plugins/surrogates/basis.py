"""Orthonormal Legendre basis on [-1, 1]^d with hyperbolic (q-norm) truncation (thesis §3.5, Eqs. 3.5-3.7).

The multi-index set is A = {α : (Σ_i α_i^q)^(1/q) <= p}, enumerated by numpoly in chaospy's
``generate_expansion`` order (graded, constant term first). The design matrix Ψ_ij = Π_k P̃_{α_jk}(z_ik) uses the
orthonormal Legendre polynomials P̃_n = sqrt(2n+1) P_n (unit variance under the uniform measure on [-1, 1]);
only the non-zero entries of each multi-index are multiplied, so building Ψ needs O(n · nnz(A)) work and no
symbolic polynomials.
"""

from __future__ import annotations

import numpy as np
import numpoly
from scipy.special import eval_legendre

from spflow.core.errors import ParameterError

__all__ = ["multi_indices", "legendre_table", "design_matrix"]


def multi_indices(dimension: int, degree: int, q: float = 1.0) -> np.ndarray:
    """Multi-indices (P, d) of total q-norm <= ``degree``, constant first (Eq. 3.7 truncation)."""
    if dimension < 1:
        raise ParameterError(f"basis dimension must be >= 1, got {dimension}")
    if degree < 0:
        raise ParameterError(f"basis degree must be >= 0, got {degree}")
    if not 0.0 < q <= 1.0:
        raise ParameterError(f"basis q-norm must be in (0, 1], got {q}")
    idx = numpoly.glexindex(start=0, stop=degree + 1, dimensions=dimension, cross_truncation=q,
                            graded=True, reverse=True)
    return np.asarray(idx, dtype=np.int64).reshape(-1, dimension)


def legendre_table(z: np.ndarray, degree: int) -> np.ndarray:
    """Orthonormal Legendre values P̃_n(z) for n = 0..degree: array (n_points, d, degree + 1)."""
    n = np.arange(degree + 1)
    return eval_legendre(n, z[..., None]) * np.sqrt(2 * n + 1)


def design_matrix(z: np.ndarray, indices: np.ndarray) -> np.ndarray:
    """Ψ (n_points, P) at points ``z`` in [-1, 1]^d for multi-indices ``indices`` (P, d)."""
    z = np.atleast_2d(np.asarray(z, dtype=float))
    if z.shape[1] != indices.shape[1]:
        raise ParameterError(f"basis: points have {z.shape[1]} coordinates, multi-indices {indices.shape[1]}")
    table = legendre_table(z, int(indices.max(initial=0)))
    psi = np.ones((z.shape[0], indices.shape[0]))
    for k in range(indices.shape[1]):
        cols = np.flatnonzero(indices[:, k])
        if cols.size:
            psi[:, cols] *= table[:, k, indices[cols, k]]
    return psi
