"""Dispersion of surfactant, polymer, anions and divalent cations on the 2-D grid (Eq. 1.9), operator split after the
advective step.

Eq. 1.9 per phase ``l`` with the phase Darcy velocity ``u_l = f_l u``:
``phi S_l K_l = phi S_l D delta + alpha_T |u_l| delta + (alpha_L - alpha_T) u_l u_l^T / |u_l|``. Its diagonal in PV
units (``u`` in units of ``u_ref``, lengths in units of ``L``) is

    k_l,xx = f_l (alpha_L U_x^2 + alpha_T U_y^2) / |U| + phi S_l D / (u_ref L),
    k_l,yy = f_l (alpha_L U_y^2 + alpha_T U_x^2) / |U| + phi S_l D / (u_ref L),

with the cell-centre velocity ``(U_x, U_y)`` (mean of the two faces) and ``alpha_T = ratio * alpha_L`` (the
parameter catalogue has no transverse dispersivity: the ratio is an argument of ``simulate2d``). The phase
coefficients are summed over the carrying phases of each species with ``cell_properties.species_dispersion`` (the
1-D weights). Approximation: the off-diagonal term ``(alpha_L - alpha_T) f_l U_x U_y / |U|`` is dropped -- it
vanishes where the flow is along x or y and is small where |U_y| << |U_x| (most of the core).

Discretisation: backward Euler, split by direction (x sweeps along the rows, then y sweeps along the columns), each
sweep the 1-D tridiagonal solve ``transport.solve_dispersion`` with the face coefficient the mean of the two cells
and zero dispersive flux through every boundary; each sweep is conservative, unconditionally stable and positivity
preserving. For a uniform flow along x the x sweep is the 1-D dispersion step.
"""

import math

from numba import njit

from .. import kernel_inputs as K
from .. import state_layout as L
from .. import transport as T
from ..cell_properties import species_dispersion
from ..kernel import apply_dispersion, dispersion_inputs

__all__ = ["directional_coefficients", "dispersion_step"]


@njit(cache=True, error_model="numpy")
def directional_coefficients(pr, prm, ux, vy, nx, ny, alpha_t_ratio, coef_x, coef_y):
    """Species coefficients (rows ``kernel.D_*``) along x ``coef_x[4, n]`` and y ``coef_y[4, n]``."""
    dm = prm[K.DMOL] * prm[K.PHI] / (prm[K.UT] * prm[K.LENGTH])
    for iy in range(ny):
        for ix in range(nx):
            i = iy * nx + ix
            uc = 0.5 * (ux[iy, ix] + ux[iy, ix + 1])
            vc = 0.5 * (vy[iy, ix] + vy[iy + 1, ix])
            speed = math.sqrt(uc * uc + vc * vc)
            wx = uc * uc / speed if speed > 0.0 else 0.0
            wy = vc * vc / speed if speed > 0.0 else 0.0
            kx0 = 0.0
            kx1 = 0.0
            kx2 = 0.0
            ky0 = 0.0
            ky1 = 0.0
            ky2 = 0.0
            for l in range(3):
                a_l = prm[K.ALPHA_D + l]
                a_t = alpha_t_ratio * a_l
                f = pr[L.F1 + l, i]
                diff = dm * pr[L.S1 + l, i]
                kx = f * (a_l * wx + a_t * wy) + diff
                ky = f * (a_l * wy + a_t * wx) + diff
                if l == 0:
                    kx0, ky0 = kx, ky
                elif l == 1:
                    kx1, ky1 = kx, ky
                else:
                    kx2, ky2 = kx, ky
            kw, ks, kp = species_dispersion(pr, i, kx0, kx1, kx2)
            coef_x[0, i] = kw
            coef_x[1, i] = kw
            coef_x[2, i] = ks
            coef_x[3, i] = kp
            kw, ks, kp = species_dispersion(pr, i, ky0, ky1, ky2)
            coef_y[0, i] = kw
            coef_y[1, i] = kw
            coef_y[2, i] = ks
            coef_y[3, i] = kp


@njit(cache=True, error_model="numpy")
def dispersion_step(st, pr, e3, nx, ny, dt, dx, dy, d_stor, d_conc, d_coef, coef_x, coef_y, work_c, work_d, jd):
    """One split backward-Euler dispersion step of length ``dt`` (PV); ``d_stor`` holds the polymer storage of
    ``kernel.polymer_storage``; ``work_c``, ``work_d`` ``[4, max(nx, ny)]`` and ``jd`` ``[4, max(nx, ny) + 1]``."""
    n = nx * ny
    lam = dt / (dx * dx)
    dispersion_inputs(st, pr, e3, n, d_stor, d_conc, d_coef)
    for iy in range(ny):
        s = iy * nx
        T.solve_dispersion(d_stor[:, s:s + nx], d_conc[:, s:s + nx], coef_x[:, s:s + nx], nx, lam, work_c, work_d,
                           jd)
        apply_dispersion(st[:, s:s + nx], nx, lam, jd)
    if ny > 1:
        lam = dt / (dy * dy)
        dispersion_inputs(st, pr, e3, n, d_stor, d_conc, d_coef)
        for ix in range(nx):
            T.solve_dispersion(d_stor[:, ix::nx], d_conc[:, ix::nx], coef_y[:, ix::nx], ny, lam, work_c, work_d, jd)
            apply_dispersion(st[:, ix::nx], ny, lam, jd)
