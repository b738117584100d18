"""Zero-shear polymer-solution viscosity: Flory-Huggins concentration law with a salinity power law (Eqs. 2.1-2.2).

Units: viscosities in cP, polymer concentration ``cp`` in wt %, effective salinity ``csep`` and ``cse1`` in meq/ml;
``ap1``, ``ap2``, ``ap3`` in (wt %)^-1, (wt %)^-2, (wt %)^-3; ``sslope`` dimensionless.
"""

from numba import njit


@njit(cache=True, error_model="numpy")
def zero_shear_viscosity(mu_w, cp, csep, ap1, ap2, ap3, sslope, cse1):
    """``mu_p0 = mu_w [1 + (AP1 Cp + AP2 Cp^2 + AP3 Cp^3) C_SEP^SSLOPE]`` (cP), Eqs. 2.1-2.2.

    The thesis prints the bracket as ``(A1 + A2 Cp^2 + A3 Cp^3)``, which drops a ``Cp`` from the first term; the
    UTCHEM form of UTCHEM-9.0 Technical Documentation §2 (``AP1 Cp``) is used, so that ``mu_p0 = mu_w`` at ``Cp = 0``.
    Choice for CSE1: the UTCHEM guide defines CSE1 as the salinity below which the polymer viscosity is salinity
    independent, so ``C_SEP`` is floored at CSE1 (``max(csep, cse1)``) -- the viscosity is continuous in salinity and
    stays finite as ``csep -> 0`` for a negative SSLOPE (HPAM).
    """
    csep_eff = csep if csep > cse1 else cse1
    multiplier = (ap1 + (ap2 + ap3 * cp) * cp) * cp
    return mu_w * (1.0 + multiplier * csep_eff**sslope)
