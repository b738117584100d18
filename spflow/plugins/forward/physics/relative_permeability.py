"""Corey relative permeability with normalized saturation (thesis Eqs. 1.6-1.7, 2.14)."""

from numba import njit


@njit(cache=True, error_model="numpy")
def normalized_saturation(s, s1r, s2r, s3r, s_lr):
    """``S_bar = (S_l - S_lr) / (1 - S1r - S2r - S3r)`` clipped to [0, 1], Eqs. 1.7/2.14.

    ``s_lr`` is the residual of phase l itself (one of ``s1r``, ``s2r``, ``s3r``). The thesis prints the denominator of
    Eq. 2.14 as ``sum S_lr``; Eq. 1.7 and UTCHEM use ``1 - sum S_lr``, which is used here. If the residuals sum to 1 or
    more (no mobile window) the result is the step 0/1 on ``s > s_lr``.
    """
    window = 1.0 - s1r - s2r - s3r
    if window <= 0.0:
        return 1.0 if s > s_lr else 0.0
    sbar = (s - s_lr) / window
    if sbar < 0.0:
        return 0.0
    if sbar > 1.0:
        return 1.0
    return sbar


@njit(cache=True, error_model="numpy")
def corey(kr0, sbar, n):
    """Corey law ``k_r = k_r^0 S_bar^n``, Eqs. 1.6/2.14 (``sbar`` in [0, 1], exponent ``n`` > 0).

    The end points of the mobile window (``S_bar = 1``: ``1^n = 1``; ``S_bar = 0`` with ``n > 0``: ``0^n = +0``,
    IEEE/C99 ``pow``) are returned without calling ``pow``, with the same result bits; they are frequent in a flood
    (phases at or below their residual, or at their maximum saturation)."""
    if sbar == 1.0:
        return kr0 * 1.0
    if sbar == 0.0 and n > 0.0:
        return kr0 * 0.0
    return kr0 * sbar**n
