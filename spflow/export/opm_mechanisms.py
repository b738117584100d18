"""Which parts of an spflow coreflood model OPM Flow's polymer model can express, and what to do with the rest.

OPM Flow (Debian release 2022.10) solves a black-oil water/oil model with a polymer tracer in the water phase:
viscosity multiplier vs concentration (PLYVISC), Langmuir-like adsorption table (PLYADS), dead pore space, residual
resistance factor acting through the adsorbed amount and rock density (PLYROCK). It has no surfactant model, no
salinity dependence of the polymer viscosity beyond one fixed table, no physical dispersion, no capillary
desaturation and no kinetic adsorption. :func:`check_mechanisms` lists every mechanism of the resolved model that
is active and outside that set; :func:`approximations` turns each into the printed approximation made when the
caller passes ``approximate=True``. Shear thinning (PLYSHLOG) is not mapped yet: it is refused as well.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from spflow.core.errors import ParameterError
from spflow.plugins.forward import units

__all__ = ["Mechanism", "check_mechanisms", "refuse_or_note", "OpmExportError"]


class OpmExportError(ParameterError):
    """The model holds mechanisms an OPM Flow deck cannot express (and ``approximate`` was not requested)."""


@dataclass(frozen=True)
class Mechanism:
    """An active mechanism OPM Flow cannot express: its name, why it is active, the approximation if allowed."""

    name: str
    reason: str
    approximation: str


def _polymer_salinities(sched) -> set[float]:
    return {s.salinity_ppm for s in sched.slugs if s.polymer_ppm > 0.0}


def check_mechanisms(sched, p: dict[str, float], s: dict[str, float]) -> list[Mechanism]:
    """Every active mechanism of schedule ``sched``, resolved parameters ``p`` and effect strengths ``s`` that OPM
    Flow's polymer model cannot express (an empty list: the export is exact up to table interpolation)."""
    found = []
    has_polymer = any(sl.polymer_ppm > 0.0 for sl in sched.slugs)
    surf = [sl.name for sl in sched.slugs if sl.surfactant_ppm > 0.0]
    if surf:
        found.append(Mechanism(
            "surfactant", f"slugs {surf} inject surfactant (phase behaviour, IFT, microemulsion viscosity, "
            "surfactant adsorption, capillary desaturation by low IFT)",
            "surfactant dropped: those slugs inject their brine and polymer only"))
    salinity_matters = has_polymer and s["polymer_salinity"] > 0.0 and p["SSLOPE"] != 0.0
    if salinity_matters:
        sal = sorted({sl.salinity_ppm for sl in sched.slugs})
        poly = sorted(_polymer_salinities(sched))
        if len(sal) > 1:
            found.append(Mechanism(
                "salinity_dependence", f"the slugs inject {len(sal)} salinities {sal} ppm and the polymer viscosity "
                "depends on salinity (C_SEP^SSLOPE, Eq. 2.2); PLYVISC holds one salinity",
                f"PLYVISC at the salinity of the first polymer slug ({poly[0]:g} ppm) everywhere"))
        anions, divalent = units.tds_ppm_to_anions(poly[0]), units.tds_ppm_to_divalent(poly[0])
        if not (math.isclose(p["C50"], anions, rel_tol=1e-6) and math.isclose(p["C60"], divalent, rel_tol=1e-6)):
            found.append(Mechanism(
                "connate_salinity", f"the connate brine (C50 = {p['C50']:g}, C60 = {p['C60']:g} meq/ml) differs from "
                f"the polymer slugs' brine ({anions:.4g}, {divalent:.4g} meq/ml at {poly[0]:g} ppm); polymer meeting "
                "connate water sees another viscosity in spflow", "the polymer slugs' salinity everywhere"))
    if has_polymer and s["shear_thinning"] > 0.0:
        found.append(Mechanism(
            "shear_thinning", f"effect shear_thinning = {s['shear_thinning']:g} (Meter law, Eq. 2.4); the export does "
            "not map it to PLYSHLOG", "Newtonian polymer solution at its zero-shear viscosity (Eq. 2.1)"))
    disp = [n for n in ("ALPHAL1", "ALPHAL2", "ALPHAL3", "DMOL") if p[n] > 0.0]
    if s["dispersion"] > 0.0 and disp:
        found.append(Mechanism(
            "dispersion", f"effect dispersion = {s['dispersion']:g} with {', '.join(disp)} > 0 (Eq. 1.9); OPM Flow "
            "has no physical dispersion", "physical dispersion dropped (OPM's numerical dispersion only)"))
    if s["capillary_desaturation"] > 0.0 and any(p[n] > 0.0 for n in ("T11", "T22", "T33")):
        found.append(Mechanism(
            "capillary_desaturation", f"effect capillary_desaturation = {s['capillary_desaturation']:g} with trapping "
            "parameters T11/T22/T33 > 0 (Eqs. 2.12-2.13); OPM has no trapping-number model",
            "low-capillary-number relative permeabilities (S1RWC, S2RWC, P1RWC, P2RWC, E1WC, E2WC) throughout"))
    if has_polymer and s["kinetic_adsorption"] > 0.0:
        found.append(Mechanism(
            "kinetic_adsorption", f"effect kinetic_adsorption = {s['kinetic_adsorption']:g}; OPM adsorbs at "
            "equilibrium", "equilibrium (instantaneous) Langmuir adsorption"))
    rk_on = has_polymer and s["permeability_reduction"] > 0.0
    ads_on = s["polymer_adsorption"] > 0.0 and (p["AD41"] > 0.0 or p["AD42"] > 0.0)
    if rk_on and not ads_on:
        found.append(Mechanism(
            "permeability_reduction_without_adsorption", "permeability reduction is on but polymer adsorption is off; "
            "OPM's residual resistance acts only through adsorbed polymer (Rk = 1 + (RRF - 1) Ca / Ca_max)",
            "permeability reduction dropped"))
    elif rk_on and p["BRK"] != p["B4D"]:
        found.append(Mechanism(
            "permeability_reduction_shape", f"BRK = {p['BRK']:g} differs from B4D = {p['B4D']:g}: spflow's R_k "
            "(Eq. 2.7) and OPM's adsorption-driven R_k have different concentration shapes",
            "R_k matched at the largest injected polymer concentration (the plateau), not below it"))
    return found


def refuse_or_note(found: list[Mechanism], approximate: bool, log) -> list[str]:
    """Raise :class:`OpmExportError` naming every mechanism in ``found`` unless ``approximate``; otherwise print
    (``log``) and return one note per approximation made."""
    if not found:
        return []
    if not approximate:
        lines = "; ".join(f"{m.name} ({m.reason})" for m in found)
        raise OpmExportError(
            f"OPM Flow cannot express these active mechanisms: {lines}. Switch them off (effects=..., a schedule "
            "without them) or pass approximate=True (CLI --approximate) to export with the printed approximations")
    notes = [f"APPROXIMATION {m.name}: {m.approximation} ({m.reason})" for m in found]
    for note in notes:
        log(note)
    return notes
