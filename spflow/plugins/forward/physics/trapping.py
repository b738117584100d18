"""Capillary desaturation: trapping number, residual saturations and end-point interpolation (thesis Eqs. 2.12-2.13;
UTCHEM ITRAP, UTCHEM-9.0 Technical Documentation §2)."""

import math

from numba import njit


@njit(cache=True, error_model="numpy")
def trapping_number(darcy_grad_potential_k, sigma):
    """``N_T = |k grad(Phi)| / sigma`` (dimensionless), SI units.

    ``darcy_grad_potential_k`` is the permeability times the potential gradient driving the conjugate phase, in Pa
    (m^2 times Pa/m; in 1-D without gravity ``k dPhi/dx = u mu / k_r``); ``sigma`` the IFT in N/m (1 mN/m = 1e-3 N/m).
    ``sigma <= 0`` returns +inf (fully miscible: the residuals reach their high-N_T values).
    """
    if sigma <= 0.0:
        return math.inf
    return abs(darcy_grad_potential_k) / sigma


@njit(cache=True, error_model="numpy")
def residual_saturation(s_low, s_high, t_l, n_t, tau):
    """``S_lr = S_lr^high + (S_lr^low - S_lr^high) / (1 + T_l N_T^tau)``, Eq. 2.12 without the ``min(S_l, .)``.

    ``s_low``/``s_high`` residuals at low/high trapping number, ``t_l`` = T11/T22/T33, ``tau`` the exponent (1 in the
    thesis). The solver applies ``min(S_l, .)`` itself.
    """
    return s_high + (s_low - s_high) / (1.0 + t_l * n_t**tau)


@njit(cache=True, error_model="numpy")
def endpoint_interpolation(v_low, v_high, s_conj_r, s_conj_low, s_conj_high):
    """``v = v_low + (S_l'r^low - S_l'r) / (S_l'r^low - S_l'r^high) (v_high - v_low)``, Eq. 2.13.

    Interpolates an end-point relative permeability (or a Corey exponent) between its low and high trapping-number
    values by the residual saturation ``s_conj_r`` of the conjugate phase l'. If ``s_conj_low == s_conj_high`` the
    interpolation is undefined and ``v_low`` is returned. The fraction is clipped to [0, 1]: the residual the solver
    uses is ``min(S_l', S_l'r)`` (Eq. 2.12), which falls below ``S_l'r^high`` where the conjugate phase itself is
    below its high-N_T residual, and Eq. 2.13 must not extrapolate past the high-N_T end point (a negative end point,
    i.e. a negative mobility, otherwise).
    """
    span = s_conj_low - s_conj_high
    if span == 0.0:
        return v_low
    fraction = min(max((s_conj_low - s_conj_r) / span, 0.0), 1.0)
    return v_low + fraction * (v_high - v_low)
