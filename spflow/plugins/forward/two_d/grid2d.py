"""Geometry of the 2-D core (thesis Fig. 1.1 in x-y): cells, faces, transmissibilities, wells.

Dimensionless units as in the 1-D model: lengths in units of the core length ``L`` (``x`` in [0, 1], ``y`` in
[0, W/L]), velocities in units of the mean Darcy velocity ``u_ref = q / A``, time in injected pore volumes (uniform
porosity). Cells are numbered row by row, ``i = iy * nx + ix`` (x fastest), so each row is a contiguous 1-D core.

Two-point flux: with the cell conductance ``c_i = (k_i / k_ref) lambda_T,i`` (1/(Pa s)), the flow (per unit
thickness, in units of ``u_ref L``) through the face between cells ``a`` and ``b`` is ``T_ab (P_a - P_b)`` with the
harmonic-average transmissibility ``T_ab = 2 c_a c_b / (c_a + c_b) * (face length / centre distance)`` and the
scaled pressure ``P = p k_ref / (u_ref L)`` (Pa s). Boundaries (Fig. 1.1): no flow through ``y = 0`` and
``y = W/L``; a line injector along ``x = 0`` at one (unknown) well pressure with the constant total rate, connected to
every first cell by the half-cell transmissibility ``2 c dy/dx`` (so the rate splits by transmissibility and
mobility); a producer line along ``x = 1`` at ``P = 0`` through the half-cell transmissibility of the last cells.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["Grid2D", "harmonic"]


def harmonic(a, b):
    """Harmonic mean ``2ab/(a + b)`` (0 where both are 0)."""
    s = a + b
    return np.divide(2.0 * a * b, s, out=np.zeros_like(s, dtype=np.float64), where=s > 0.0)


@dataclass(frozen=True)
class Grid2D:
    """``nx`` x ``ny`` cells of a core of aspect ratio ``aspect = W/L``; ``kappa[ny, nx] = k / k_ref``."""

    nx: int
    ny: int
    aspect: float
    kappa: np.ndarray

    @property
    def n(self) -> int:
        return self.nx * self.ny

    @property
    def dx(self) -> float:
        return 1.0 / self.nx

    @property
    def dy(self) -> float:
        return self.aspect / self.ny

    def transmissibilities(self, mobility: np.ndarray):
        """Face transmissibilities for the total mobility ``mobility[ny, nx]`` (1/(Pa s)): interior x faces
        ``[ny, nx - 1]``, interior y faces ``[ny - 1, nx]``, injector and producer faces ``[ny]``."""
        c = self.kappa * mobility
        gx = self.dy / self.dx
        gy = self.dx / self.dy
        tx = gx * harmonic(c[:, :-1], c[:, 1:])
        ty = gy * harmonic(c[:-1, :], c[1:, :])
        return tx, ty, 2.0 * gx * c[:, 0], 2.0 * gx * c[:, -1]

    def face_cells(self):
        """Cell pairs ``(a, b)`` of the interior x faces then the interior y faces (flattened, in the order of
        ``transmissibilities``), and the cells next to the injector and the producer."""
        idx = np.arange(self.n).reshape(self.ny, self.nx)
        a = np.concatenate([idx[:, :-1].ravel(), idx[:-1, :].ravel()])
        b = np.concatenate([idx[:, 1:].ravel(), idx[1:, :].ravel()])
        return a, b, idx[:, 0].copy(), idx[:, -1].copy()
