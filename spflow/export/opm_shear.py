"""spflow's shear thinning as OPM Flow's PLYSHLOG table (shear multiplier against the water velocity).

spflow (Meter's law, Eq. 2.4, at UTCHEM's equivalent shear rate; :mod:`spflow.plugins.forward.physics.shear_thinning`):

    mu_p = mu_w + (mu_0 - mu_w) M(gamma),   M = 1 - s + s / (1 + (gamma / gamma_half)^(POWN - 1))
    gamma = GAMMAC' u_w / sqrt(k k_rw phi S_w)                       (1/s; SI: GAMMAC' = GAMMAC x SI_FACTOR)

with ``s`` the ``shear_thinning`` strength, ``gamma_half`` GAMHF or Eq. 2.5 and ``u_w`` the water Darcy flux.

OPM Flow 2022.10 (opm-models ``BlackOilPolymerModule``, read from its source) evaluates its multiplier on every face
at the water velocity ``v = u_w / (phi (S_w - Swcr))`` (upstream ``S_w``; ``Swcr`` the critical water saturation of
the SWOF table, here ``S1RWC``), with the PLYSHLOG table (velocity in m/day in METRIC units, multiplier ``Z_ref``)
taken at the reference concentration ``c_ref`` of its first record: ``M_i = (Z_ref,i P(c_ref) - 1) / (P(c_ref) -
1)`` (``P`` the PLYVISC multiplier), and at any concentration the water viscosity is ``mu_w (1 + (P(c) - 1)
M(v))`` -- Meter's form with a concentration-independent ``M`` -- interpolated linearly in log-log, ``M = 1`` below the
first node, extrapolated above the last; ``v`` is the velocity of the sheared flow (OPM solves ``v Z(v) = v_0`` by
Newton). Since ``u_w = v phi (S_w - Swcr)``, spflow's shear rate is ``gamma = C(S_w) v`` with

    C(S_w) = GAMMAC' phi (S_w - Swcr) / sqrt(k k_rw(S_w) phi S_w)                         (1/m)

so the export writes, at log-spaced shear rates ``gamma_i``, the velocity ``v_i = gamma_i / C(S_w*)`` and
``Z_ref,i = mu_p(gamma_i, c_ref) / mu_0(c_ref)``. This is exact at every concentration (with a fixed half shear rate)
and at ``S_w = S_w*``; elsewhere OPM's equivalent shear rate is spflow's times ``C(S_w*) / C(S_w)`` (for Corey
``k_rw ~ (S_w - Swcr)^E1WC``: ``(S_w - Swcr)^(E1WC/2 - 1) sqrt(S_w)`` relative to its value at ``S_w*``). Exact when
the water saturation cannot change (``SWI >= 1 - S2RWC``, a single-phase or residual-oil core: ``S_w* = SWI``);
otherwise an approximation matched at ``S_w*`` (default ``1 - S2RWC``, the saturation behind a polymer slug that has
displaced the oil to its residual). A half shear rate of Eq. 2.5 (``IGAMHF = 1``, ``A2 != 0``: ``gamma_half ~
exp(A2 Cp)``) is exact at ``c_ref`` only.

Why not SHRATE (OPM's shear-rate form, ``SHRATE v sqrt(phi S_w / (k_rw,OPM k))``): OPM's ``k_rw,OPM`` there is ``mu_w``
times the water mobility, which holds the polymer and ``R_k`` (so its shear rate carries ``sqrt(P(c) R_k)``: measured
2.8 and 4.3 times spflow's at 1000 and 2000 ppm, ``sqrt(P)`` = 2.86 and 4.40), and OPM 2022.10 aborts (an ``isfinite``
assertion) on every face whose upstream ``k_rw`` is 0, i.e. ahead of the water front of a core at ``SWI = S1RWC``.

Wells: OPM shears the water of a polymer well connection at ``q_w / (2 pi sqrt(r_e r_w) L phi (S_w - Swcr))``
(``r_e = sqrt(DX DY / pi)``, ``L = DZ``, ``r_w`` half the COMPDAT diameter). :func:`matching_bore_diameter` chooses
``r_w = (A / (2 pi L))^2 / r_e`` (``A = DY DZ``), which makes it the blocks' ``v`` at every saturation, so the
half-block connections (the inlet and outlet of the core) see the shear of the first and last blocks.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from spflow.plugins.forward import units
from spflow.plugins.forward.physics.polymer_viscosity import zero_shear_viscosity
from spflow.plugins.forward.physics.shear_thinning import SI_FACTOR, half_shear_rate, meter_viscosity

from .opm_tables import KG_M3_PER_PPM, KG_M3_PER_WT_PERCENT, OpmTables

__all__ = ["OpmShear", "opm_shear", "shear_reference_saturation", "rate_per_velocity", "matching_bore_diameter",
           "SECONDS_PER_DAY"]

SECONDS_PER_DAY = 86400.0
#: the table runs from M = 1 - 1e-6 to M = 1e-6 (at most 20 decades either side of gamma_half)
_M_TAIL = 1.0e-6
_MAX_DECADES = 20.0


@dataclass(frozen=True)
class OpmShear:
    """PLYSHLOG of one export (see the module docstring)."""

    table: np.ndarray  # (n, 2): water velocity (m/day), Z_ref = mu_p(gamma) / mu_0 at c_ref
    rate_per_velocity: float  # C(S_w*) (1/m): spflow's shear rate per unit OPM water velocity at S_w*
    c_ref: float  # kg/m3, PLYSHLOG reference concentration
    gamma_half: float  # 1/s, at c_ref
    reference_sw: float  # S_w* where OPM's shear rate equals spflow's
    swcr: float  # critical water saturation of the SWOF table (= S1RWC)
    exact: bool  # the water saturation cannot leave S_w*


def shear_reference_saturation(p: dict[str, float], shear_sw: float | None) -> tuple[float, bool]:
    """``(S_w*, exact)``: the water saturation at which OPM's shear rate is made spflow's, and whether the saturation
    stays there (``SWI >= 1 - S2RWC``: the water saturation stays SWI)."""
    if p["SWI"] >= 1.0 - p["S2RWC"]:
        return float(p["SWI"]), True
    return (1.0 - p["S2RWC"] if shear_sw is None else float(shear_sw)), False


def rate_per_velocity(p: dict[str, float], sw: float, krw: float) -> float:
    """``C(S_w) = GAMMAC' phi (S_w - Swcr) / sqrt(k k_rw phi S_w)`` (1/m): spflow's equivalent shear rate per unit of
    OPM's water velocity ``u_w / (phi (S_w - Swcr))``."""
    phi, k = p["PORO"], p["PERM"] * units.MD_TO_M2
    return p["GAMMAC"] * SI_FACTOR * phi * (sw - p["S1RWC"]) / math.sqrt(k * krw * phi * sw)


def opm_shear(sched, p: dict[str, float], s: dict[str, float], tables: OpmTables, *, shear_sw: float | None = None,
              nodes_per_decade: int = 20) -> OpmShear | None:
    """PLYSHLOG of schedule ``sched`` (parameters ``p``, effect strengths ``s``) at the experiment's salinity (that of
    ``tables``) and largest injected polymer concentration; ``None`` when nothing is sheared (no polymer, strength 0
    or GAMMAC = 0). ``shear_sw`` overrides the matching saturation ``1 - S2RWC`` of a two-phase core."""
    strength = s["shear_thinning"]
    top_ppm = max((sl.polymer_ppm for sl in sched.slugs), default=0.0)
    if top_ppm <= 0.0 or strength <= 0.0 or p["GAMMAC"] <= 0.0:
        return None
    sw_ref, exact = shear_reference_saturation(p, shear_sw)
    krw = float(np.interp(sw_ref, tables.swof[:, 0], tables.swof[:, 1]))
    c_ref = top_ppm * KG_M3_PER_PPM
    cp = c_ref / KG_M3_PER_WT_PERCENT  # wt %
    sslope = s["polymer_salinity"] * p["SSLOPE"]
    mu_w = p["VIS1"]
    mu0 = zero_shear_viscosity(mu_w, cp, tables.csep, p["AP1"], p["AP2"], p["AP3"], sslope, p["CSE1"])
    if p["IGAMHF"] > 0.0:
        ghalf = half_shear_rate(max(tables.csep, p["CSE1"]), cp, p["A0"], p["A1"], p["A2"])
    else:
        ghalf = p["GAMHF"]
    slope = p["POWN"] - 1.0
    decades = _MAX_DECADES if slope <= 0.0 else min(_MAX_DECADES, math.log10((1.0 - _M_TAIL) / _M_TAIL) / slope)
    centre = ghalf if ghalf > 0.0 else 1.0
    n = int(math.ceil(2.0 * decades * nodes_per_decade)) + 1
    gamma = centre * 10.0 ** np.linspace(-decades, decades, n)  # 1/s
    mu = np.array([mu0 - strength * (mu0 - meter_viscosity(mu_w, mu0, g, ghalf, p["POWN"])) for g in gamma])
    c = rate_per_velocity(p, sw_ref, krw)
    return OpmShear(table=np.column_stack([gamma / c * SECONDS_PER_DAY, mu / mu0]), rate_per_velocity=float(c),
                    c_ref=c_ref, gamma_half=float(ghalf), reference_sw=float(sw_ref), swcr=float(p["S1RWC"]),
                    exact=exact)


def matching_bore_diameter(dx: float, side: float) -> float:
    """COMPDAT well-bore diameter (m) giving a connection of a block ``dx`` x ``side`` x ``side`` (m) the water velocity
    of the block's faces: ``2 r_w`` with ``r_w = (side / (2 pi))^2 / r_e``, ``r_e = sqrt(dx side / pi)``."""
    re = math.sqrt(dx * side / math.pi)
    return 2.0 * (side / (2.0 * math.pi)) ** 2 / re
