"""Interfacial tension between the microemulsion and an excess phase: modified Chun-Huh law with Hirasaki's
correction (thesis Eqs. 2.9-2.10; UTCHEM IFT = 1). IFTs in mN/m (= dyne/cm); compositions in volume fractions.
"""

import math

from numba import njit

_HIRASAKI_NORM = 1.0 - math.exp(-math.sqrt(2.0))


@njit(cache=True, error_model="numpy")
def hirasaki_factor(c1l, c2l, c3l, c13, c23, c33):
    """``F_l = [1 - exp(-sqrt(sum_k (C_kl - C_k3)^2))] / [1 - exp(-sqrt(2))]``, Eq. 2.10.

    ``(c1l, c2l, c3l)`` is the composition of the excess phase l, ``(c13, c23, c33)`` that of the ME. F = 1 between
    pure water and pure oil (distance sqrt(2)) and F -> 0 as the two phases become identical (plait point).
    """
    d1 = c1l - c13
    d2 = c2l - c23
    d3 = c3l - c33
    return (1.0 - math.exp(-math.sqrt(d1 * d1 + d2 * d2 + d3 * d3))) / _HIRASAKI_NORM


@njit(cache=True, error_model="numpy")
def chun_huh_ift(r, f, sigma_ow, chuh, ahuh):
    """``sigma_l3 = sigma_ow exp(-a R) + (c F / R^2)(1 - exp(-a R^3))`` (mN/m), Eq. 2.9.

    ``r`` solubilization ratio R_l3 (>= 0), ``f`` Hirasaki factor F_l, ``sigma_ow`` oil-water IFT (mN/m, = 10^XIFTW),
    ``chuh`` = c (CHUH, mN/m), ``ahuh`` = a (AHUH). The second term is evaluated as
    ``c F a R g(a R^3)`` with ``g(x) = (1 - exp(-x)) / x`` (``g(0) = 1``, via ``expm1``), which is the same quantity
    without the 0/0 at ``R = 0``; hence ``sigma -> sigma_ow`` as ``R -> 0``.
    """
    x = ahuh * r * r * r
    g = -math.expm1(-x) / x if x > 0.0 else 1.0
    return sigma_ow * math.exp(-ahuh * r) + chuh * f * ahuh * r * g
