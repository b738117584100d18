"""Ogata-Banks breakthrough with dispersion and retardation (Ogata & Banks 1961; 1-D form of thesis Eq. 1.9).

Continuous step injection into a semi-infinite medium, ``R c_t + c_x = (1/Pe) c_xx`` in dimensionless form
(``t_D`` in PV, ``Pe = L/alpha_L``, ``R = (1 - phi_IPV) + D`` in the scaled-IPV form):
``c/c_0 = 1/2 [erfc((x - t/R)/(2 sqrt(t/(R Pe)))) + exp(Pe x) erfc((x + t/R)/(2 sqrt(t/(R Pe))))]``.
The second term is evaluated as ``exp(Pe x - z^2) erfcx(z)`` to avoid overflow.
"""

import numpy as np
from scipy.optimize import brentq
from scipy.special import erfc, erfcx


def _check(name: str, value: float) -> None:
    if not value > 0.0:
        raise ValueError(f"{name} must be > 0, got {value}")


def ogata_banks(x_d, t_d, peclet: float, retardation: float = 1.0):
    """Relative concentration ``c/c_0`` at ``x_D`` (>= 0) and ``t_D`` (> 0, PV) for Peclet number ``Pe = L/alpha_L``."""
    _check("peclet", peclet)
    _check("retardation", retardation)
    x = np.asarray(x_d, dtype=float)
    t = np.asarray(t_d, dtype=float)
    if np.any(t <= 0.0):
        raise ValueError("t_d (injected PV) must be > 0")
    if np.any(x < 0.0):
        raise ValueError("x_d must be >= 0")
    width = 2.0 * np.sqrt(t / (retardation * peclet))
    z_minus = (x - t / retardation) / width
    z_plus = (x + t / retardation) / width
    return 0.5 * (erfc(z_minus) + np.exp(peclet * x - z_plus**2) * erfcx(z_plus))


def ogata_banks_time_at(level: float, peclet: float, retardation: float = 1.0, x_d: float = 1.0) -> float:
    """Injected PV at which ``c/c_0`` at ``x_D`` reaches ``level`` in (0, 1) (e.g. 0.5 = effluent midpoint)."""
    if not 0.0 < level < 1.0:
        raise ValueError(f"level must be in (0, 1), got {level}")
    _check("x_d", x_d)
    center = retardation * x_d
    return brentq(lambda t: float(ogata_banks(x_d, t, peclet, retardation)) - level, 1e-6 * center, 10.0 * center)


def retarded_midpoint_pv(ipv: float, retardation: float) -> float:
    """Dispersion-free effluent midpoint ``t_D,50% = (1 - phi_IPV) + D`` (PV) at ``S_w = 1``."""
    if not 0.0 <= ipv < 1.0:
        raise ValueError(f"ipv must be in [0, 1), got {ipv}")
    if not retardation >= 0.0:
        raise ValueError(f"retardation must be >= 0, got {retardation}")
    return (1.0 - ipv) + retardation
