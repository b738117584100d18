"""Explicit conservative transport of the six components on the 2-D grid (Eq. 1.3 summed per component, no
gravity, no capillary pressure), in the units of ``grid2d`` (time in PV, velocities in units of ``u_ref``).

Face fluxes are the face velocity times the component fractional flux of the upwind side:

* x faces: each row is a 1-D core, and ``transport.advective_fluxes`` (the 1-D TVD / upwind scheme with the van Leer
  limiter, injector composition at face 0, first order at the first interior and the producer face) gives the
  component fractions of all its faces; its Lax-Wendroff Courant factor uses ``dt/dx`` times the row's mean x
  velocity. Where the x velocity of an interior face is negative (back flow around a low-permeability inclusion)
  the face takes the first-order fractions of the cell downstream in x (its upwind cell) instead;
* y faces: each column is a 1-D core too, swept with the same ``transport.advective_fluxes`` twice -- along the
  column for the faces with upward flow (V > 0) and along the reversed column (a negative-stride view) for the faces
  with downward flow -- so each face gets the TVD fractions of its own upwind stencil (first order at the first
  interior face from the wall the flow comes from); the Lax-Wendroff Courant factor is ``dt/dy`` times the column's
  mean |V|. The fluxes of the faces at ``y = 0, W/L`` are multiplied by V = 0 (no flow). With ``tvd = False`` both
  directions are first-order upwind (the fractions of the cell the flow leaves). The scheme is mirror-symmetric in
  y: the downward sweep of a flipped column is the upward sweep of the original.

The update ``m_i -= dt [(U F)_e - (U F)_w] / dx + dt [(V G)_n - (V G)_s] / dy`` is conservative; the time step is
``dt = cfl / max_i s_i (max|U|_i / dx + max|V|_i / dy)`` with the wave-speed bound ``s_i`` of ``cell_properties``
and the largest face velocities around cell ``i``, which reduces to the 1-D step for a uniform flow along x.
"""

import numpy as np
from numba import njit

from .. import state_layout as L
from .. import transport as T

__all__ = ["advective_fluxes_2d", "conservative_update", "stable_step", "outlet_rates"]


@njit(cache=True, error_model="numpy")
def advective_fluxes_2d(pr, nx, ny, ux, vy, tvd, lam_x, lam_y, e3, e4, inj3, inj4, inj5, inj6, fx, gy):
    """Component fractional fluxes of the x faces ``fx[NFLUX, ny, nx + 1]`` and y faces ``gy[NFLUX, ny + 1, nx]``
    (to be multiplied by the face velocities ``ux``, ``vy``); ``lam_x = dt/dx``, ``lam_y = dt/dy``."""
    for iy in range(ny):
        s = iy * nx
        mean_u = 0.0
        for j in range(nx + 1):
            mean_u += ux[iy, j]
        mean_u /= nx + 1
        row_flux = fx[:, iy, :]
        T.advective_fluxes(pr[:, s:s + nx], nx, tvd, lam_x * mean_u, e3, e4, inj3, inj4, inj5, inj6, row_flux)
        for j in range(1, nx):
            if ux[iy, j] < 0.0:
                T.upwind_cell_fluxes(pr, s + j, row_flux, j)
    down = np.empty((T.NFLUX, ny + 1))
    for ix in range(nx):
        mean_v = 0.0
        up_flow = False
        down_flow = False
        for j in range(1, ny):
            mean_v += abs(vy[j, ix])
            up_flow |= vy[j, ix] >= 0.0
            down_flow |= vy[j, ix] < 0.0
        courant = lam_y * mean_v / (ny + 1)
        column = pr[:, ix::nx]
        face = gy[:, :, ix]
        if up_flow:
            T.advective_fluxes(column, ny, tvd, courant, e3, e4, 0.0, 0.0, 0.0, 0.0, face)
        if down_flow:
            T.advective_fluxes(column[:, ::-1], ny, tvd, courant, e3, e4, 0.0, 0.0, 0.0, 0.0, down)
            for j in range(1, ny):
                if vy[j, ix] < 0.0:
                    for r in range(T.NFLUX):
                        face[r, j] = down[r, ny - j]


@njit(cache=True, error_model="numpy")
def conservative_update(st, fx, gy, ux, vy, nx, ny, dt, dx, dy, new):
    """``new[6, n]`` = ``st[:6]`` minus ``dt`` times the divergence of the component fluxes."""
    for iy in range(ny):
        for ix in range(nx):
            i = iy * nx + ix
            for r in range(6):
                div_x = (ux[iy, ix + 1] * fx[r, iy, ix + 1] - ux[iy, ix] * fx[r, iy, ix]) / dx
                div_y = (vy[iy + 1, ix] * gy[r, iy + 1, ix] - vy[iy, ix] * gy[r, iy, ix]) / dy
                new[r, i] = st[r, i] - dt * (div_x + div_y)


@njit(cache=True, error_model="numpy")
def stable_step(pr, ux, vy, nx, ny, dx, dy, cfl):
    """``cfl / max_i s_i (max|U|_i / dx + max|V|_i / dy)`` (infinite when nothing moves)."""
    rate = 0.0
    for iy in range(ny):
        for ix in range(nx):
            u = max(abs(ux[iy, ix]), abs(ux[iy, ix + 1]))
            v = max(abs(vy[iy, ix]), abs(vy[iy + 1, ix]))
            r = pr[L.SPEED, iy * nx + ix] * (u / dx + v / dy)
            if r > rate:
                rate = r
    return cfl / rate if rate > 0.0 else 1.0e300


@njit(cache=True, error_model="numpy")
def outlet_rates(pr, fx, ux, nx, ny, face, out):
    """Component rates through the injector (``face = 0``) or producer (``face = nx``) line in PV per PV time
    (``out[:6]``) and, for the producer, the rate of the polymer-carrying phase (``out[6]``)."""
    for r in range(7):
        out[r] = 0.0
    for iy in range(ny):
        u = ux[iy, face] / ny
        for r in range(6):
            out[r] += u * fx[r, iy, face]
        i = iy * nx + nx - 1
        pcx = int(pr[L.PCX, i])
        out[6] += u * (pr[L.F1, i] if pcx == 1 else (pr[L.F1 + 2, i] if pcx == 3 else 0.0))
