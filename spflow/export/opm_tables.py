"""spflow's property models tabulated as OPM Flow's keyword tables (SWOF, PLYVISC, PLYADS, PLYROCK, PLYMAX).

Every table is evaluated with spflow's own property functions (``spflow.plugins.forward.physics``) at the deck's
nodes, in OPM's METRIC units:

* SWOF: low-capillary-number Corey curves (Eqs. 1.6-1.7, 2.14) of the aqueous and oleic phases, with the
  residuals clipped to the phase saturation as the forward model does (``k_rw = P1RWC`` above ``1 - S2RWC``,
  ``k_row = P2RWC`` below ``S1RWC``); the Pc column is the Brooks-Corey capillary pressure (Eq. 1.8, at the oil-water
  IFT, bar) when the ``capillary_pressure`` effect is on, else 0.
* PLYVISC: ``mu_p0 / mu_w`` of the Flory-Huggins law (Eqs. 2.1-2.2) at the polymer effective salinity (Eq. 2.3) of
  the experiment's polymer slugs; concentrations in kg/m3 (1 ppm = 1 mg/l = 1e-3 kg/m3, so 1 wt % = 10 kg/m3: the
  polymer solution is taken at 1000 kg/m3).
* PLYADS: the Langmuir isotherm (Eqs. 2.15-2.16) ``C^ = a c / (1 + b c)`` (wt % x pore volume per pore volume),
  converted to kg polymer per kg rock: ``phi 10 C^ / (rho_r (1 - phi))`` (OPM stores ``(1 - phi) rho_r Ca`` per
  bulk volume, spflow ``phi C^``).
* PLYROCK: dead pore space ``1 - EPHI4`` (OPM multiplies the water saturation by ``1 - IPV`` in the polymer
  storage, as spflow's ``EPHI4 S_w c``), residual resistance factor ``RRF = R_k`` at full adsorption, rock density,
  adsorption index 2 (no desorption: spflow's adsorption is irreversible), and the maximum adsorption ``Ca_max``.
  OPM's permeability reduction is ``R_k = 1 + (RRF - 1) Ca / Ca_max``; with ``Ca_max`` the Langmuir plateau
  ``a / b`` and ``BRK = B4D`` it equals spflow's ``1 + (R_k,max - 1) BRK c / (1 + BRK c)`` (Eq. 2.7) exactly.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from spflow.plugins.forward import units
from spflow.plugins.forward.physics.adsorption import langmuir_a
from spflow.plugins.forward.physics.capillary_pressure import brooks_corey_pc
from spflow.plugins.forward.physics.effective_salinity import polymer_effective_salinity
from spflow.plugins.forward.physics.permeability_reduction import max_permeability_reduction
from spflow.plugins.forward.physics.polymer_viscosity import zero_shear_viscosity
from spflow.plugins.forward.physics.relative_permeability import corey, normalized_saturation

__all__ = ["OpmTables", "opm_tables", "KG_M3_PER_PPM", "KG_M3_PER_WT_PERCENT", "PA_PER_BAR"]

#: polymer ppm (mg/l) -> kg/m3
KG_M3_PER_PPM = 1.0e-3
#: polymer wt % -> kg/m3 (solution density 1000 kg/m3)
KG_M3_PER_WT_PERCENT = 10.0
PA_PER_BAR = 1.0e5


@dataclass(frozen=True)
class OpmTables:
    """The property tables and scalars of one export (METRIC units; see the module docstring)."""

    swof: np.ndarray  # (n, 4): Sw, krw, krow, Pcow (bar)
    plyvisc: np.ndarray  # (m, 2): c (kg/m3), viscosity multiplier
    plyads: np.ndarray  # (m, 2): c (kg/m3), adsorbed (kg/kg rock)
    dead_pore_space: float
    rrf: float
    rock_density: float  # kg/m3 of rock (grain) volume
    adsorption_index: int
    max_adsorption: float  # kg/kg
    c_max: float  # kg/m3, the PLYMAX / table end
    salinity_ppm: float  # salinity at which PLYVISC, PLYADS and R_k,max are evaluated
    csep: float  # polymer effective salinity, meq/ml (Eq. 2.3)


def _saturation_nodes(n: int, s1r: float, s2r: float) -> np.ndarray:
    return np.unique(np.round(np.concatenate([np.linspace(0.0, 1.0, n), [s1r, 1.0 - s2r]]), 9))


def _swof(p, s, n_nodes):
    s1r, s2r = p["S1RWC"], p["S2RWC"]
    sw = _saturation_nodes(n_nodes, s1r, s2r)
    rows = np.zeros((sw.size, 4))
    pc0 = s["capillary_pressure"] * p["CPC0"]
    for i, s1 in enumerate(sw):
        s2 = 1.0 - s1
        r1, r2 = min(s1r, s1), min(s2r, s2)  # residuals clipped to the phase saturation, as the forward model
        krw = corey(p["P1RWC"], normalized_saturation(s1, r1, r2, 0.0, r1), p["E1WC"]) if s1 > 0.0 else 0.0
        kro = corey(p["P2RWC"], normalized_saturation(s2, r1, r2, 0.0, r2), p["E2WC"]) if s2 > 0.0 else 0.0
        pc = 0.0
        if pc0 > 0.0:
            pc = brooks_corey_pc(pc0, normalized_saturation(s1, r1, r2, 0.0, r1), p["EPC0"], 1.0, 1.0) / PA_PER_BAR
        rows[i] = (s1, krw, kro, pc)
    return rows


def _concentration_nodes(c_max: float, n: int) -> np.ndarray:
    """Quadratically graded nodes on [0, c_max]: fine near 0, where the Langmuir isotherm bends."""
    return c_max * np.linspace(0.0, 1.0, n) ** 2


def opm_tables(sched, p: dict[str, float], s: dict[str, float], *, rock_density: float = 2650.0,
               swof_nodes: int = 401, polymer_nodes: int = 201, c_max_ppm: float | None = None) -> OpmTables:
    """The OPM tables of schedule ``sched`` with resolved parameters ``p`` and effect strengths ``s``.

    The polymer tables run from 0 to the largest injected polymer concentration (``c_max_ppm`` overrides it, e.g.
    for a field deck injecting more); the salinity is that of the first polymer slug (the first slug without
    polymer)."""
    poly = [sl for sl in sched.slugs if sl.polymer_ppm > 0.0]
    salinity = (poly[0] if poly else sched.slugs[0]).salinity_ppm
    top_ppm = c_max_ppm if c_max_ppm is not None else max((sl.polymer_ppm for sl in poly), default=1000.0)
    c_max = top_ppm * KG_M3_PER_PPM
    c5, c6 = units.tds_ppm_to_anions(salinity), units.tds_ppm_to_divalent(salinity)
    csep = polymer_effective_salinity(c5, c6, 1.0, p["BETAP"])
    sslope = s["polymer_salinity"] * p["SSLOPE"]

    c = _concentration_nodes(c_max, polymer_nodes)
    c_wt = c / KG_M3_PER_WT_PERCENT
    mult = np.array([zero_shear_viscosity(1.0, x, csep, p["AP1"], p["AP2"], p["AP3"], sslope, p["CSE1"])
                     for x in c_wt])

    phi = p["PORO"]
    a = langmuir_a(s["polymer_adsorption"] * p["AD41"], s["polymer_adsorption"] * p["AD42"], csep, 0.0, 1.0)
    b = p["B4D"]
    per_pv_to_kg_kg = phi * KG_M3_PER_WT_PERCENT / (rock_density * (1.0 - phi))
    ads = per_pv_to_kg_kg * a * c_wt / (1.0 + b * c_wt)

    rrf, max_ads = 1.0, 1.0  # RRF = 1: no reduction (Ca_max then only has to be > 0)
    if poly and s["permeability_reduction"] > 0.0 and p["BRK"] > 0.0 and a > 0.0:
        rkmax = max_permeability_reduction(p["CRK"], p["AP1"], max(csep, p["CSE1"]), sslope,
                                           p["PERM"] * units.MD_TO_DARCY, phi, p["RKCAP"])
        rrf = 1.0 + s["permeability_reduction"] * (rkmax - 1.0)
        top_wt = max(sl.polymer_ppm for sl in poly) * KG_M3_PER_PPM / KG_M3_PER_WT_PERCENT
        ads_top = per_pv_to_kg_kg * a * top_wt / (1.0 + b * top_wt)
        bc = p["BRK"] * top_wt
        # Ca_max such that (RRF - 1) Ca(c_top) / Ca_max = (R_k,max - 1) BRK c_top / (1 + BRK c_top): the Langmuir
        # plateau a / b when BRK = B4D (then exact at every concentration)
        max_ads = ads_top * (1.0 + bc) / bc
    ipv = s["inaccessible_pore_volume"] * (1.0 - p["EPHI4"])  # 1 - EPHI4 of the forward model
    return OpmTables(
        swof=_swof(p, s, swof_nodes),
        plyvisc=np.column_stack([c, mult]),
        plyads=np.column_stack([c, ads]),
        dead_pore_space=float(ipv),
        rrf=float(rrf),
        rock_density=float(rock_density),
        adsorption_index=2,
        max_adsorption=float(max_ads),
        c_max=float(c_max),
        salinity_ppm=float(salinity),
        csep=float(csep),
    )
