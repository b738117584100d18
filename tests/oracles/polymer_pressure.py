"""Single-phase polymer flood pressure drop: piston front, resistance factors (Darcy with resistance factors, Lake
1989 ch. 5; thesis Eqs. 2.6-2.8).

A polymer step injected at constant rate into a water-filled core advances as a piston at ``x_f/L = t_D / R`` with
``R = (1 - phi_IPV) + D``; with Darcy's law in series ``dp(t) = q/(k A) [mu_p R_k x_f + mu_w (L - x_f)]``, i.e.
``dp/dp_w = 1 + (RF - 1) min(t_D/R, 1)`` with the resistance factor ``RF = mu_p R_k / mu_w``. After a water
post-flush the permeability reduction stays (irreversible): ``RRF = R_k``.
"""

import numpy as np


def flory_huggins_viscosity(c_wt_pct: float, mu_w: float, ap1: float, ap2: float, ap3: float,
                            salinity_factor: float = 1.0) -> float:
    """Zero-shear polymer viscosity ``mu_w [1 + (AP1 c + AP2 c^2 + AP3 c^3) C_SEP^S_P]`` (Eq. 2.1 form).

    ``c_wt_pct`` polymer concentration in wt %; ``salinity_factor`` = ``C_SEP^SSLOPE`` (1 without salinity effect);
    the result has the unit of ``mu_w``.
    """
    if not c_wt_pct >= 0.0:
        raise ValueError(f"c_wt_pct must be >= 0, got {c_wt_pct}")
    if not mu_w > 0.0:
        raise ValueError(f"mu_w must be > 0, got {mu_w}")
    return mu_w * (1.0 + (ap1 * c_wt_pct + ap2 * c_wt_pct**2 + ap3 * c_wt_pct**3) * salinity_factor)


def permeability_reduction(c_wt_pct: float, brk: float, crk: float, ap1: float, perm_darcy: float,
                           porosity: float, salinity_factor: float = 1.0, cap: float | None = None) -> float:
    """Permeability-reduction factor ``R_k`` of thesis Eqs. 2.7-2.8 for an isotropic core (``k_x = k_y``).

    ``R_k,max = [1 - c_rk (AP1 C_SEP^S_P)^(1/3) / (sqrt(k_x k_y)/phi)^(1/2)]^-4`` with ``k`` in darcy (UTCHEM: CRK in
    darcy^1/2), optionally limited to ``cap`` (``min``); ``R_k = 1 + (R_k,max - 1) b_rk C / (1 + b_rk C)``.
    """
    if not c_wt_pct >= 0.0:
        raise ValueError(f"c_wt_pct must be >= 0, got {c_wt_pct}")
    if not perm_darcy > 0.0:
        raise ValueError(f"perm_darcy must be > 0, got {perm_darcy}")
    if not 0.0 < porosity <= 1.0:
        raise ValueError(f"porosity must be in (0, 1], got {porosity}")
    base = 1.0 - crk * (ap1 * salinity_factor) ** (1.0 / 3.0) / np.sqrt(perm_darcy / porosity)
    if not base > 0.0:
        raise ValueError(f"R_k,max undefined: 1 - c_rk (...)^(1/3)/(k/phi)^(1/2) = {base} <= 0")
    rk_max = base**-4.0
    if cap is not None:
        rk_max = min(rk_max, cap)
    return 1.0 + (rk_max - 1.0) * brk * c_wt_pct / (1.0 + brk * c_wt_pct)


def piston_pressure_ratio(t_d, resistance_factor: float, retardation_pv: float):
    """``dp(t)/dp_water`` for a piston polymer front: ``1 + (RF - 1) min(t_D/R, 1)`` (``R`` = front retardation)."""
    if not resistance_factor > 0.0:
        raise ValueError(f"resistance_factor must be > 0, got {resistance_factor}")
    if not retardation_pv > 0.0:
        raise ValueError(f"retardation_pv must be > 0, got {retardation_pv}")
    t = np.asarray(t_d, dtype=float)
    if np.any(t < 0.0):
        raise ValueError("t_d (injected PV) must be >= 0")
    return 1.0 + (resistance_factor - 1.0) * np.minimum(t / retardation_pv, 1.0)
