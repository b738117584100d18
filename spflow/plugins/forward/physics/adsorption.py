"""Langmuir adsorption of surfactant and polymer (thesis Eqs. 2.15-2.16; UTCHEM-9.0 Technical Documentation §2).

Units (UTCHEM pore-volume convention): surfactant concentrations as volume fractions, polymer in wt %; ``a`` is
dimensionless, ``b`` is the inverse of the concentration unit (vol/vol for surfactant, 1/(wt %) for polymer);
salinity in meq/ml, ``a2`` in ml/meq; the permeabilities ``kref`` and ``k`` in the same unit (UTCHEM REFK in md).
"""

import math

from numba import njit


@njit(cache=True, error_model="numpy")
def langmuir_a(a1, a2, cse, kref, k):
    """``a = (a1 + a2 C_SE) (k_ref / k)^(1/2)``, Eq. 2.16; the permeability factor is applied only when ``kref > 0``
    (UTCHEM IADK = 1), otherwise it is 1."""
    a = a1 + a2 * cse
    if kref > 0.0:
        a *= math.sqrt(kref / k)
    return a


@njit(cache=True, error_model="numpy")
def langmuir_adsorbed(c_total, a, b):
    """Adsorbed concentration solving ``C_hat = min(C_tot, a (C_tot - C_hat) / (1 + b (C_tot - C_hat)))``, Eq. 2.15.

    ``c_total`` is the overall concentration per pore volume (fluid plus adsorbed, ``C~`` of Eq. 2.15). With the
    fluid part ``x = C_tot - C_hat`` the isotherm gives ``b x^2 + (1 + a - b C_tot) x - C_tot = 0``; the physical root
    is the non-negative one, evaluated in the cancellation-free form
    ``x = 2 C_tot / (q + sqrt(q^2 + 4 b C_tot))`` for ``q = 1 + a - b C_tot >= 0`` and
    ``x = (-q + sqrt(q^2 + 4 b C_tot)) / (2 b)`` otherwise (then ``b > 0``). The adsorbed amount is returned as the
    isotherm value ``a x / (1 + b x)`` (accurate also when it is a tiny fraction of ``C_tot``, where ``C_tot - x``
    would cancel); in exact arithmetic it equals ``C_tot - x <= C_tot``, and the ``min`` of Eq. 2.15 guards the
    round-off. ``c_total <= 0`` returns 0.
    """
    if c_total <= 0.0:
        return 0.0
    q = 1.0 + a - b * c_total
    root = math.sqrt(q * q + 4.0 * b * c_total)
    if q >= 0.0:
        x = 2.0 * c_total / (q + root)
    else:
        x = (root - q) / (2.0 * b)
    adsorbed = a * x / (1.0 + b * x)
    return adsorbed if adsorbed < c_total else c_total


@njit(cache=True, error_model="numpy")
def retardation(a, b, c_inj):
    """Dilute pore-volume retardation ``D = C_hat(C_J) / C_J = a / (1 + b C_J)`` (UTCHEM-9.0 Technical Documentation
    §2), dimensionless."""
    return a / (1.0 + b * c_inj)
