"""Polymer permeability reduction R_k and its maximum R_k,max (thesis Eqs. 2.7-2.8; UTCHEM).

Units: ``k_darcy`` is the permeability in darcy (so CRK is in darcy^(1/2) (wt %)^(1/3), a length), ``csep`` the
polymer effective salinity in meq/ml (already floored at CSE1 by the caller), ``cp`` in wt %, ``brk`` in 1/(wt %),
``ap1`` in 1/(wt %); porosity and R_k are dimensionless.
"""

from numba import njit


@njit(cache=True, error_model="numpy")
def max_permeability_reduction(crk, ap1, csep, sslope, k_darcy, phi, cap=10.0):
    """``R_k,max = min([1 - CRK (AP1 C_SEP^SSLOPE)^(1/3) / (k/phi)^(1/2)]^-4, cap)``, Eq. 2.8.

    ``k_darcy`` is ``sqrt(k_x k_y)`` in darcy. The thesis prints ``max[..., 10]``, which would make every R_k,max at
    least 10 and contradicts its own RRF experiment (Fig. 2.4); UTCHEM caps the value instead, so ``min(value, cap)``
    is implemented with the default cap 10. The bracket reaches 0 when the polymer coil size
    ``CRK (AP1 C_SEP^SSLOPE)^(1/3)`` equals the pore-size scale ``(k/phi)^(1/2)`` (pores plugged); for a bracket
    ``<= 0`` the cap is returned, the limit of the formula from above.
    """
    bracket = 1.0 - crk * (ap1 * csep**sslope) ** (1.0 / 3.0) / (k_darcy / phi) ** 0.5
    if bracket <= 0.0:
        return cap
    value = bracket**-4.0
    return value if value < cap else cap


@njit(cache=True, error_model="numpy")
def permeability_reduction(rkmax, brk, cp):
    """``R_k = 1 + (R_k,max - 1) BRK Cp / (1 + BRK Cp)``, Eq. 2.7 (``cp`` in wt %, ``brk`` in 1/(wt %)).

    The caller passes the running maximum of the polymer concentration to make the reduction irreversible.
    """
    bc = brk * cp
    return 1.0 + (rkmax - 1.0) * bc / (1.0 + bc)
