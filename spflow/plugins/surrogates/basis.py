"""Orthonormal polynomial basis with hyperbolic (q-norm) truncation (thesis §3.5, Eqs. 3.4-3.6).

The multi-index set is A = {α : (Σ_i α_i^q)^(1/q) <= p}, enumerated by numpoly in chaospy's
``generate_expansion`` order (graded, constant term first). The design matrix Ψ_ij = Π_k φ^(k)_{α_jk}(z_ik) takes
each coordinate's factor from its own orthonormal family (:mod:`.orthonormal_polynomials`: Legendre for uniform
inputs, P̃_n = sqrt(2n+1) P_n on [-1, 1] from Bonnet's recurrence; Hermite for normal and lognormal ones; Jacobi for
beta ones); the multi-index set and its truncation do not depend on the families.

Fast evaluation: every multi-index α with a non-zero entry has a *parent*, α with its last non-zero entry set to 0,
and Ψ_α = Ψ_parent · P̃_{α_k}(z_k). Ordering the terms by their number of non-zero entries (adding the missing
parents of an index set that is not downward closed) builds each column of Ψ with one multiplication per point —
P multiplications per point instead of nnz(A) — in one compiled pass over contiguous rows. The plan (parents, order)
depends only on the multi-indices and is cached.
"""

from __future__ import annotations

from collections.abc import Sequence
from functools import lru_cache

import numpy as np
import numpoly
from numba import njit

from spflow.core.errors import ParameterError

from .orthonormal_polynomials import LEGENDRE, PolynomialFamily, univariate_table

__all__ = ["multi_indices", "design_matrix"]


def multi_indices(dimension: int, degree: int, q: float = 1.0) -> np.ndarray:
    """Multi-indices (P, d) of total q-norm <= ``degree``, constant first (hyperbolic truncation of §3.5)."""
    if dimension < 1:
        raise ParameterError(f"basis dimension must be >= 1, got {dimension}")
    if degree < 0:
        raise ParameterError(f"basis degree must be >= 0, got {degree}")
    if not 0.0 < q <= 1.0:
        raise ParameterError(f"basis q-norm must be in (0, 1], got {q}")
    idx = numpoly.glexindex(start=0, stop=degree + 1, dimensions=dimension, cross_truncation=q,
                            graded=True, reverse=True)
    return np.asarray(idx, dtype=np.int64).reshape(-1, dimension)


def _drop_last_nonzero(rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Each row with its last non-zero entry zeroed, and the position of that entry (0 for the zero row)."""
    nonzero = rows > 0
    last = rows.shape[1] - 1 - np.argmax(nonzero[:, ::-1], axis=1)
    parents = rows.copy()
    has = np.flatnonzero(nonzero.any(axis=1))
    parents[has, last[has]] = 0
    return parents, last


@lru_cache(maxsize=64)
def _plan(key: bytes, shape: tuple[int, int]) -> tuple[np.ndarray, ...]:
    """Evaluation plan of a multi-index set: rows to fill in dependency order, their parents' rows, the dimension and
    degree of the factor they add. Rows 0..P-1 of the work array are the requested terms; missing ancestors follow."""
    indices = np.frombuffer(key, dtype=np.int64).reshape(shape)
    chain, current = [indices, np.zeros((1, shape[1]), np.int64)], indices
    while current.any():
        current, _ = _drop_last_nonzero(current)
        chain.append(current)
    rows, inverse = np.unique(np.concatenate(chain), axis=0, return_inverse=True)
    inverse = inverse.ravel()
    if np.unique(inverse[: shape[0]]).size != shape[0]:
        raise ParameterError("basis: the multi-indices contain repeated rows")
    slot = np.full(rows.shape[0], -1, dtype=np.int64)
    slot[inverse[: shape[0]]] = np.arange(shape[0])
    extra = np.flatnonzero(slot < 0)
    slot[extra] = shape[0] + np.arange(extra.size)
    parents, last = _drop_last_nonzero(rows)
    both, both_inverse = np.unique(np.concatenate([rows, parents]), axis=0, return_inverse=True)
    both_inverse = both_inverse.ravel()
    to_row = np.empty(both.shape[0], dtype=np.int64)
    to_row[both_inverse[: rows.shape[0]]] = np.arange(rows.shape[0])
    parent = to_row[both_inverse[rows.shape[0]:]]
    level = np.count_nonzero(rows, axis=1)
    order = np.argsort(level, kind="stable")
    degree = rows[np.arange(rows.shape[0]), last]
    return slot[order], slot[parent[order]], last[order], degree[order], rows.shape[0]


@njit(cache=True)
def _fill(table, target, parent, dim, degree, work):  # pragma: no cover - compiled
    n = table.shape[2]
    for r in range(target.size):
        t = target[r]
        if degree[r] == 0:
            for i in range(n):
                work[t, i] = 1.0
        else:
            p, k, m = parent[r], dim[r], degree[r]
            for i in range(n):
                work[t, i] = work[p, i] * table[k, m, i]


def design_matrix(z: np.ndarray, indices: np.ndarray, families: Sequence[PolynomialFamily] | None = None) -> np.ndarray:
    """Ψ (n_points, P) at reference points ``z`` (n_points, d) for multi-indices ``indices`` (P, d) (a Fortran-ordered
    view). ``families`` gives each coordinate's orthonormal family (:mod:`.orthonormal_polynomials`); None means
    Legendre for all, z in [-1, 1]^d."""
    z = np.atleast_2d(np.asarray(z, dtype=float))
    indices = np.ascontiguousarray(indices, dtype=np.int64)
    if indices.ndim != 2 or z.shape[1] != indices.shape[1]:
        raise ParameterError(f"basis: points have {z.shape[1]} coordinates, multi-indices have shape {indices.shape}")
    if (indices < 0).any():
        raise ParameterError("basis: multi-indices must be non-negative")
    target, parent, dim, degree, n_rows = _plan(indices.tobytes(), indices.shape)
    families = (LEGENDRE,) * z.shape[1] if families is None else tuple(families)
    table = univariate_table(z.T, families, int(indices.max(initial=0)))
    work = np.empty((n_rows, z.shape[0]))
    _fill(table, target, parent, dim, degree, work)
    return work[: indices.shape[0]].T
