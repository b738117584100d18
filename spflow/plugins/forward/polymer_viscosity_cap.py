"""The physical cap on a run's polymer-solution viscosity: a cross-parameter rule checked before any work.

Each parameter of Eqs. 2.1-2.3 has physical bounds on its own (``parameters.PARAMETERS``), but together they allow
absurd fluids: ``C_SEP^SSLOPE`` alone reaches 1e40 (``SSLOPE = -5``, ``CSE1 = 1e-8`` meq/ml), and with AP3 up to
1e6 (wt %)^-3 the zero-shear viscosity of a polymer slug can exceed 1e10 cP. Such a fluid is not a polymer solution
(the thesis's HPAM fit gives ~47 cP for the 3300 ppm SP slug of BCF1 at 9400 ppm TDS), and it makes the carrier
phase's fractional flow rise from 0 to 1 over an oil saturation of ``(k_w^0 mu_o / (k_o^0 mu_p))^(1/n)`` above its
residual: the exact ``df/dS`` there, which sets the explicit step, grows without bound (docs/forward_model.md, "Run
budgets": 4 of 4 over-budget draws examined had such fluids).

The rule: the zero-shear polymer-solution viscosity ``mu_p0`` (Eq. 2.1, before shear thinning, which only lowers
it) at the largest polymer concentration injected and at the effective salinity ``C_SEP`` (Eq. 2.3, floored at
CSE1 as in the kernel) that maximises it over the run -- the lowest of the initial brine and the slugs for a
negative SSLOPE, the highest for a positive one; transport mixes fluids, so every cell's ``C_SEP`` lies between
those of the fluids in place and injected -- must not exceed ``MAX_POLYMER_VISCOSITY_CP``. A run above it is
rejected with a ``ParameterError`` naming the parameters; nothing is clipped.
"""

from __future__ import annotations

from spflow.core.errors import ParameterError

from . import units
from .physics.polymer_viscosity import zero_shear_viscosity

__all__ = ["MAX_POLYMER_VISCOSITY_CP", "polymer_salinity_range", "peak_polymer_viscosity", "check_polymer_viscosity"]

#: cap on the zero-shear polymer-solution viscosity of a run (cP): two decades above the viscosity of the EOR
#: polymer solutions of the thesis (HPAM, Eq. 2.1 fits at 9400-22000 ppm TDS: tens of cP) and above the thesis's
#: own fit extrapolated to the CSE1 floor at 5000 ppm (~3e4 cP); beyond it the fluid is a gel, not a displacing
#: solution (docs/forward_model.md, "Polymer-viscosity cap")
MAX_POLYMER_VISCOSITY_CP = 1.0e5


def polymer_salinity_range(resolved: dict[str, float], schedule) -> tuple[float, float]:
    """``(lowest, highest)`` polymer effective salinity ``max(C51 + (BETAP - 1) C61, CSE1)`` (meq/ml, Eq. 2.3) of
    the initial brine (C50, C60) and of every slug of ``schedule`` (a validated ``Schedule``)."""
    betap, floor = resolved["BETAP"], resolved["CSE1"]
    values = [resolved["C50"] + (betap - 1.0) * resolved["C60"]]
    for slug in schedule.slugs:
        values.append(units.tds_ppm_to_anions(slug.salinity_ppm)
                      + (betap - 1.0) * units.tds_ppm_to_divalent(slug.salinity_ppm))
    values = [max(v, floor) for v in values]
    return min(values), max(values)


def peak_polymer_viscosity(resolved: dict[str, float], strengths: dict[str, float], schedule):
    """``(mu_p0, polymer_ppm, C_SEP)``: the largest zero-shear polymer-solution viscosity (cP) a run can reach, the
    injected polymer concentration (ppm) and the effective salinity (meq/ml) it is reached at. The kernel's SSLOPE
    is ``polymer_salinity x SSLOPE`` (``kernel_inputs``). ``mu_p0 = VIS1`` when no slug carries polymer."""
    ppm = max((slug.polymer_ppm for slug in schedule.slugs), default=0.0)
    cp = units.polymer_ppm_to_wt_percent(ppm)
    sslope = strengths["polymer_salinity"] * resolved["SSLOPE"]
    best = None
    for csep in polymer_salinity_range(resolved, schedule):
        mu = float(zero_shear_viscosity(resolved["VIS1"], cp, csep, resolved["AP1"], resolved["AP2"],
                                        resolved["AP3"], sslope, resolved["CSE1"]))
        if best is None or mu > best[0]:
            best = (mu, ppm, csep)
    return best


def check_polymer_viscosity(resolved: dict[str, float], strengths: dict[str, float], schedule) -> None:
    """Raise ``ParameterError`` if the run's peak polymer-solution viscosity (:func:`peak_polymer_viscosity`)
    exceeds ``MAX_POLYMER_VISCOSITY_CP``; the message names the parameters of Eqs. 2.1-2.3, their values and the
    allowed range of the Flory-Huggins factor."""
    mu, ppm, csep = peak_polymer_viscosity(resolved, strengths, schedule)
    if mu <= MAX_POLYMER_VISCOSITY_CP:
        return
    p = resolved
    cp = units.polymer_ppm_to_wt_percent(ppm)
    sslope = strengths["polymer_salinity"] * p["SSLOPE"]
    factor = (p["AP1"] * cp + p["AP2"] * cp**2 + p["AP3"] * cp**3) * csep**sslope
    allowed = MAX_POLYMER_VISCOSITY_CP / p["VIS1"] - 1.0
    raise ParameterError(
        f"polymer-solution viscosity of schedule {schedule.name!r} is {mu:.3g} cP, above the physical cap "
        f"{MAX_POLYMER_VISCOSITY_CP:g} cP: parameters AP1 = {p['AP1']:g}, AP2 = {p['AP2']:g}, AP3 = {p['AP3']:g}, "
        f"SSLOPE = {p['SSLOPE']:g} (x polymer_salinity strength {strengths['polymer_salinity']:g}), "
        f"CSE1 = {p['CSE1']:g} meq/ml, BETAP = {p['BETAP']:g} and VIS1 = {p['VIS1']:g} cP give "
        f"(AP1 Cp + AP2 Cp^2 + AP3 Cp^3) C_SEP^SSLOPE = {factor:.3g} (Eqs. 2.1-2.3) at the largest injected "
        f"polymer concentration Cp = {ppm:g} ppm and the run's most viscosifying effective salinity C_SEP = "
        f"{csep:.3g} meq/ml; allowed range of that factor [0, {allowed:.6g}] (= cap / VIS1 - 1)"
    )
