"""Point-by-point numba loops of the lab fits over the forward simulator's own kernels (compiled, cached).

Kept apart from the fits so that reading a lab table, declaring a fit stage or listing stages does not import numba:
:mod:`.adsorption_fit` and :mod:`.polymer_rheology` import this module when they evaluate their models.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from spflow.plugins.forward.physics.adsorption import langmuir_a, retardation
from spflow.plugins.forward.physics.effective_salinity import polymer_effective_salinity
from spflow.plugins.forward.physics.polymer_viscosity import zero_shear_viscosity
from spflow.plugins.forward.physics.shear_thinning import half_shear_rate, meter_viscosity

__all__ = ["isotherm_loop", "viscosity_loop", "meter_loop"]


@njit(cache=True)
def isotherm_loop(conc, cse, a1, a2, b):
    """Adsorbed concentration ``C a/(1 + b C)`` with ``a = a1 + a2 C_SE`` (Eqs. 2.15-2.16) per point."""
    out = np.empty(conc.size)
    for i in range(conc.size):
        a = langmuir_a(a1, a2, cse[i], 0.0, 1.0)
        out[i] = conc[i] * retardation(a, b, conc[i])
    return out


@njit(cache=True)
def viscosity_loop(cp, c51, c61, gamma, mu_w, cse1, ap1, ap2, ap3, sslope, betap, pown, a0, a1, a2):
    """Polymer-solution viscosity per point (Eqs. 2.1-2.5)."""
    out = np.empty(cp.size)
    for i in range(cp.size):
        csep = polymer_effective_salinity(c51[i], c61[i], 1.0, betap)
        mu0 = zero_shear_viscosity(mu_w, cp[i], csep, ap1, ap2, ap3, sslope, cse1)
        ghalf = half_shear_rate(max(csep, cse1), cp[i], a0, a1, a2)
        out[i] = meter_viscosity(mu_w, mu0, gamma[i], ghalf, pown)
    return out


@njit(cache=True)
def meter_loop(mu_w, mu0, gamma, ghalf, pown):
    """Meter-law viscosity (Eq. 2.4) of one sweep per shear rate."""
    out = np.empty(gamma.size)
    for i in range(gamma.size):
        out[i] = meter_viscosity(mu_w, mu0, gamma[i], ghalf, pown)
    return out
