"""Implicit pressure of the 2-D IMPES step (thesis sec. 1.6: the summed transport equations, Eqs. 1.3-1.4 without
gravity): ``div(k lambda_T grad p) = 0`` on the two-point-flux grid of ``grid2d`` with the line injector at constant
total rate and the producer at constant pressure.

The matrix is the symmetric positive-definite M-matrix of the two-point scheme (one row per cell). The injector's
single unknown well pressure is eliminated by linearity: with the producer at 0 the solution scales with the well
pressure, so the system is solved once for a unit well pressure and scaled to the prescribed total rate.

Solver (``method``):

* ``"pcg"`` (default): conjugate gradients (``scipy.sparse.linalg.cg``) preconditioned with the sparse LU
  (``splu``) of a recent pressure matrix, warm-started from the previous pressure, to the relative residual
  ``rtol`` (default 1e-12). The mobility changes little from step to step, so an old factorisation is a nearly exact
  preconditioner: measured on the 400 x 80 water flood (``benchmarks/bench_two_d.py``), 5 iterations to 1e-12 with
  the LU of the previous matrix, 8 with one 50 solves older, 13 with the initial (t = 0) one. The matrix is
  refactored (and solved directly) at the first solve and whenever a solve needs more than ``max_growth``
  iterations more than the first solve after the last factorisation, or does not converge in ``MAX_ITERATIONS``.
  One LU solve costs ~1/30 of a factorisation (2 ms vs 60-120 ms at 400 x 80); over the 1-PV run, 21
  factorisations for 4084 solves, 8.1 iterations per solve, a solve ~1/3 of the time of a direct one.
* ``"direct"``: factor and solve every matrix (the reference).

Both use ``splu`` with the minimum-degree ordering of ``A^T + A`` (the fastest of SuperLU's orderings for this
5-point matrix, ~1.4e6 factor entries at 400 x 80; COLAMD and MMD on ``A^T A`` fill more, reverse Cuthill-McKee 3.5x
more) in symmetric mode without pivoting (the matrix is symmetric positive definite and diagonally dominant).

**Flux correction.** The face fluxes must be divergence-free to round-off: the component updates are conservative
whatever the velocity field, but the volumes of the components in a cell only keep summing to one when the fluxes
are discretely divergence-free, and the homogeneous 2-D run reproduces the 1-D solution only when the row
velocities are uniform to round-off. An iterative solve leaves a residual ``r = b - A p``: the net volume gained by
each cell. The net gains are computed from the face velocities themselves (differences of the face flows, not
``b - A p``, whose round-off scales with the transmissibilities rather than the flows) and removed by adding to
every x face of a row the running sum of the gains along the row up to that face (each cell passes on what it
gained; the row's sum leaves through the producer face). The fluxes then balance to round-off whatever the solve's
accuracy; the velocities' error is that of the pressure, ~``rtol``. (The direct solve's round-off-level imbalance
gets the same correction.)

The sparsity pattern is fixed, so the matrix values are scattered from the face transmissibilities with one
precomputed sparse product. The PCG's vector operations are too small for threaded BLAS: run the solver inside
``threadpoolctl.threadpool_limits(1, "blas")`` (``simulate2d`` does) -- measured, a CG solve with two OpenBLAS
threads took 4.6x the time of one with one thread.
"""

from __future__ import annotations

import time
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


METHODS = ("pcg", "direct")
MAX_ITERATIONS = 100


class PressureSolver:
    """Assembles and solves the pressure system of one ``Grid2D`` (pattern and scatter built once); keeps the
    factorisation and the last solution between calls (``method``, ``rtol``, ``max_growth``: module docstring).
    Counters: ``n_solves``, ``n_factorizations``, ``n_iterations`` (PCG iterations), ``wall_s`` (time in ``solve``)."""

    def __init__(self, grid: Grid2D, method: str = "pcg", rtol: float = 1e-12, max_growth: int = 3):
        if method not in METHODS:
            raise ValueError(f"method must be one of {METHODS}, got {method!r}")
        self.grid = grid
        self.method = method
        self.rtol = rtol
        self.max_growth = max_growth
        self.n_solves = 0
        self.n_factorizations = 0
        self.n_iterations = 0
        self.wall_s = 0.0
        self._lu = None
        self._prec = None
        self._first_its = None
        self._p1 = None
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

    def _factor_and_solve(self, mat, rhs):
        self._lu = spla.splu(mat, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0,
                             options={"SymmetricMode": True})
        self._prec = spla.LinearOperator(mat.shape, self._lu.solve, dtype=np.float64)
        self._first_its = None
        self.n_factorizations += 1
        return self._lu.solve(rhs)

    def _unit_solution(self, mat, rhs):
        """Cell pressures for a unit injector pressure (producer at 0)."""
        if self.method == "direct" or self._lu is None:
            return self._factor_and_solve(mat, rhs)
        its = 0

        def count(_):
            nonlocal its
            its += 1

        p1, info = spla.cg(mat, rhs, x0=self._p1, rtol=self.rtol, atol=0.0, M=self._prec, maxiter=MAX_ITERATIONS,
                           callback=count)
        self.n_iterations += its
        if info != 0:
            return self._factor_and_solve(mat, rhs)
        if self._first_its is None:
            self._first_its = its
        elif its > self._first_its + self.max_growth:
            self._lu = None  # refactor at the next solve
        return p1

    def solve(self, mobility: np.ndarray) -> PressureField:
        """Pressure and face velocities for the total mobility ``mobility[ny, nx]`` (1/(Pa s))."""
        start = time.perf_counter()
        g = self.grid
        tx, ty, tin, tout = g.transmissibilities(mobility)
        t_all = np.concatenate([tx.ravel(), ty.ravel(), tin, tout])
        mat = sp.csc_matrix((self._scatter @ t_all, self._indices, self._indptr), shape=(g.n, g.n))
        rhs = np.zeros(g.n)
        rhs[self._inj] = tin
        p1 = self._unit_solution(mat, rhs)
        self._p1 = p1
        self.n_solves += 1
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
        # the flux correction: each cell passes on its net gain (0 for an exact solve) to the next x face
        gained = (ux[:, :-1] - ux[:, 1:]) * g.dy + (vy[:-1, :] - vy[1:, :]) * g.dx
        ux[:, 1:] += np.cumsum(gained, axis=1) / g.dy
        self.wall_s += time.perf_counter() - start
        return PressureField(pc, scale, ux, vy)
