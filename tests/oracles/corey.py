"""Corey relative permeabilities and the water fractional flow (thesis Eqs. 1.6 and 1.11).

``S_n = (S_w - S_wc)/(1 - S_wc - S_or)``, ``k_rw = k_rw° S_n^n_w``, ``k_ro = k_ro° (1 - S_n)^n_o`` and
``f_w = (k_rw/mu_w) / (k_rw/mu_w + k_ro/mu_o)``. Viscosities may be in any one unit (cP here): only their ratio
enters ``f_w``. A chemical (polymer or surfactant) fractional-flow curve is the same object built with the chemical
curve's residuals/end points/exponents and the aqueous viscosity ``mu_p R_k``.
"""

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class CoreyFractionalFlow:
    """Two-phase Corey water fractional flow ``f_w(S_w)`` with its analytic derivative.

    Attributes: ``swc``/``sor`` residual water/oil saturations (fractions), ``krw0``/``kro0`` end-point relative
    permeabilities, ``nw``/``no`` Corey exponents (>= 1), ``mu_w``/``mu_o`` aqueous/oleic viscosities (cP).
    """

    swc: float = 0.0
    sor: float = 0.0
    krw0: float = 1.0
    kro0: float = 1.0
    nw: float = 2.0
    no: float = 2.0
    mu_w: float = 1.0
    mu_o: float = 1.0

    def __post_init__(self):
        for name in ("swc", "sor"):
            value = getattr(self, name)
            if not 0.0 <= value < 1.0:
                raise ValueError(f"{name} must be in [0, 1), got {value}")
        if self.swc + self.sor >= 1.0:
            raise ValueError(f"swc + sor must be < 1, got {self.swc + self.sor}")
        for name in ("krw0", "kro0", "mu_w", "mu_o"):
            value = getattr(self, name)
            if not value > 0.0:
                raise ValueError(f"{name} must be > 0, got {value}")
        for name in ("nw", "no"):
            value = getattr(self, name)
            if not value >= 1.0:
                raise ValueError(f"{name} must be >= 1 (finite f_w' at the end points), got {value}")

    @property
    def s_min(self) -> float:
        """Lowest mobile-water saturation ``S_wc``."""
        return self.swc

    @property
    def s_max(self) -> float:
        """Highest water saturation ``1 - S_or``."""
        return 1.0 - self.sor

    @property
    def _span(self) -> float:
        return 1.0 - self.swc - self.sor

    def normalized(self, s):
        """Normalised saturation ``S_n`` clipped to [0, 1]."""
        return np.clip((np.asarray(s, dtype=float) - self.swc) / self._span, 0.0, 1.0)

    def _mobilities(self, s):
        sn = self.normalized(s)
        lam_w = self.krw0 * sn**self.nw / self.mu_w
        lam_o = self.kro0 * (1.0 - sn) ** self.no / self.mu_o
        return sn, lam_w, lam_o

    def fw(self, s):
        """Water fractional flow ``f_w(S_w)`` (Eq. 1.11)."""
        _, lam_w, lam_o = self._mobilities(s)
        return lam_w / (lam_w + lam_o)

    def dfw(self, s):
        """Analytic derivative ``d f_w / d S_w``; zero outside ``(S_wc, 1 - S_or)``."""
        s = np.asarray(s, dtype=float)
        sn, lam_w, lam_o = self._mobilities(s)
        dlam_w = self.krw0 * self.nw * sn ** (self.nw - 1.0) / self.mu_w
        dlam_o = -self.kro0 * self.no * (1.0 - sn) ** (self.no - 1.0) / self.mu_o
        inside = (s > self.swc) & (s < 1.0 - self.sor)
        derivative = (dlam_w * lam_o - lam_w * dlam_o) / ((lam_w + lam_o) ** 2 * self._span)
        return np.where(inside, derivative, 0.0)
