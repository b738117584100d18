"""Compositional viscosity of a phase containing water, oil and surfactant (thesis Eq. 2.11; UTCHEM ALPHAV1-5)."""

import math

from numba import njit


@njit(cache=True, error_model="numpy")
def microemulsion_viscosity(c1, c2, c3, mu_w, mu_o, av1, av2, av3, av4, av5):
    """``mu = C1 mu_w e^(a1 (C2 + C3)) + C2 mu_o e^(a2 (C1 + C3)) + C3 a3 e^(a4 C1 + a5 C2)`` (cP), Eq. 2.11.

    ``c1..c3`` volume fractions of water, oil and surfactant in the phase; ``mu_w`` the aqueous (or polymer-solution)
    viscosity and ``mu_o`` the oil viscosity in cP; ``av3`` in cP, the other ALPHAV dimensionless. The thesis prints
    the last exponent as ``a4 C13 + a5 C33``; the form of the UTCHEM-9.0 Technical Documentation §2 (``a4 C1 + a5
    C2``) is used. With
    the thesis values (a3 = 0) the third term vanishes and the two forms coincide.
    """
    return (
        c1 * mu_w * math.exp(av1 * (c2 + c3))
        + c2 * mu_o * math.exp(av2 * (c1 + c3))
        + c3 * av3 * math.exp(av4 * c1 + av5 * c2)
    )
