"""Implicit pressure of the 2-D IMPES step (thesis sec. 1.6: the summed transport equations, Eqs. 1.3-1.4 without
gravity): ``div(k lambda_T grad p) = 0`` on the two-point-flux grid of ``grid2d`` with the line injector at constant
total rate and the producer at constant pressure.

The matrix is the symmetric positive-definite M-matrix of the two-point scheme (one row per cell). The injector's
single unknown well pressure is eliminated by linearity: with the producer at 0 the solution scales with the well
pressure, so the system is solved once for a unit well pressure and scaled to the prescribed total rate.

Solver: ``scipy.sparse.linalg.splu`` with the minimum-degree ordering of ``A^T + A`` (the fastest of SuperLU's
orderings for this 5-point matrix, ~1.4e6 factor entries at 400 x 80) in symmetric mode without pivoting (the
matrix is symmetric positive definite and diagonally dominant). A direct solve is used rather than a
preconditioned CG because the face fluxes must be divergence-free to round-off: the component updates are
conservative whatever the velocity field, but the volumes of the components in a cell only keep summing to one when
the fluxes are discretely divergence-free, and the homogeneous 2-D run reproduces the 1-D solution only when the
row velocities are uniform to round-off. (Measured at 400 x 80 on this machine: factor + solve ~65 ms; CG with a
Jacobi preconditioner to 1e-12 ~250 ms; CG preconditioned with the previous step's LU ~6-9 iterations, slower than
refactoring.) The sparsity pattern is fixed, so the matrix values are scattered from the face transmissibilities
with one precomputed sparse product.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from .grid2d import Grid2D

__all__ = ["PressureSolver", "PressureField"]


@dataclass
class PressureField:
    """Scaled cell pressures ``p[ny, nx]`` and well pressure ``p_well`` (Pa s: multiply by ``u_ref L / k_ref`` for
    Pa), x-face velocities ``ux[ny, nx + 1]`` (faces 0 and nx: injector, producer) and y-face velocities
    ``vy[ny + 1, nx]`` (faces 0 and ny: no flow), in units of ``u_ref``."""

    p: np.ndarray
    p_well: float
    ux: np.ndarray
    vy: np.ndarray


class PressureSolver:
    """Assembles and solves the pressure system of one ``Grid2D`` (pattern and scatter built once)."""

    def __init__(self, grid: Grid2D):
        self.grid = grid
        n = grid.n
        a, b, self._inj, self._prod = grid.face_cells()
        n_int = a.size
        faces = np.arange(n_int)
        # entries (row, col, face, sign): +T on both diagonals and -T off the diagonal of every interior face;
        # +T on the diagonal of the cells next to the injector and the producer (faces n_int .. n_int + 2 ny)
        ny = grid.ny
        bnd = np.concatenate([self._inj, self._prod])
        rows = np.concatenate([a, b, a, b, bnd])
        cols = np.concatenate([a, b, b, a, bnd])
        face = np.concatenate([faces, faces, faces, faces, n_int + np.arange(2 * ny)])
        sign = np.concatenate([np.ones(2 * n_int), -np.ones(2 * n_int), np.ones(2 * ny)])
        key = cols.astype(np.int64) * n + rows
        uniq, pos = np.unique(key, return_inverse=True)
        self._scatter = sp.csr_matrix((sign, (pos, face)), shape=(uniq.size, n_int + 2 * ny))
        self._indices = (uniq % n).astype(np.int32)
        self._indptr = np.searchsorted(uniq // n, np.arange(n + 1)).astype(np.int32)

    def solve(self, mobility: np.ndarray) -> PressureField:
        """Pressure and face velocities for the total mobility ``mobility[ny, nx]`` (1/(Pa s))."""
        g = self.grid
        tx, ty, tin, tout = g.transmissibilities(mobility)
        t_all = np.concatenate([tx.ravel(), ty.ravel(), tin, tout])
        mat = sp.csc_matrix((self._scatter @ t_all, self._indices, self._indptr), shape=(g.n, g.n))
        rhs = np.zeros(g.n)
        rhs[self._inj] = tin
        p1 = spla.splu(mat, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0,
                       options={"SymmetricMode": True}).solve(rhs)
        q1 = float(np.sum(tin * (1.0 - p1[self._inj])))
        scale = g.aspect / q1  # total inflow (per unit thickness) = W/L in units of u_ref L
        p = p1 * scale
        pc = p.reshape(g.ny, g.nx)
        ux = np.empty((g.ny, g.nx + 1))
        ux[:, 1:-1] = tx * (pc[:, :-1] - pc[:, 1:]) / g.dy
        ux[:, 0] = tin * (scale - pc[:, 0]) / g.dy
        ux[:, -1] = tout * pc[:, -1] / g.dy
        vy = np.zeros((g.ny + 1, g.nx))
        vy[1:-1, :] = ty * (pc[:-1, :] - pc[1:, :]) / g.dx
        return PressureField(pc, scale, ux, vy)
