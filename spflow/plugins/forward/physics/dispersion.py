"""Longitudinal hydrodynamic dispersion in 1-D (thesis Eq. 1.9; UTCHEM-9.0 Technical Documentation §2)."""

from numba import njit


@njit(cache=True, error_model="numpy")
def longitudinal_dispersion(phi, s, u_l, alpha_l, d_mol):
    """``phi S_l K_l = phi S_l D_m + alpha_L |u_l|`` in m^2/s, the 1-D form of Eq. 1.9 multiplied by ``phi S_l``.

    ``phi`` porosity, ``s`` phase saturation, ``u_l`` Darcy flux of phase l (m/s), ``alpha_l`` longitudinal
    dispersivity (m), ``d_mol`` molecular diffusion coefficient divided by tortuosity (m^2/s). The returned product
    multiplies ``dC/dx`` in the dispersive flux ``-phi S_l K_l dC/dx``; the Peclet number of a core of length L is
    ``u L / (phi S K) = L / alpha_L`` when diffusion is negligible.
    """
    return phi * s * d_mol + alpha_l * abs(u_l)
