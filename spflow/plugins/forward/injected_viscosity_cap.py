"""The physical cap on the viscosity of a run's injected fluids: a cross-parameter rule checked before any work.

Each parameter of Eqs. 2.1-2.3 and 2.11 has physical bounds on its own (``parameters.PARAMETERS``), but together
they allow absurd fluids: ``C_SEP^SSLOPE`` alone reaches 1e40 (``SSLOPE = -5``, ``CSE1 = 1e-8`` meq/ml), and with
AP3 up to 1e6 (wt %)^-3 the zero-shear viscosity of a polymer slug can exceed 1e10 cP; the compositional viscosity
of a surfactant solution (Eq. 2.11's ``C3 ALPHAV3 e^(ALPHAV4 C1)``, ALPHAV3 up to 20 cP, ALPHAV4 up to 20) reaches
1e7 cP. Such fluids are not EOR slugs (the thesis's calibrated SP slug of BCF1: ~47 cP), and they make the
carrier phase's fractional flow rise from 0 to 1 over a sliver of oil saturation above its residual, where the
exact ``df/dS`` that sets the explicit step grows without bound (docs/forward_model.md, "Run budgets").

The rule: the viscosity of every injected slug as the kernel computes it for an aqueous phase of that composition
-- the zero-shear polymer-solution viscosity ``mu_p0`` (Eq. 2.1, before shear thinning, which only lowers it) at
the slug's polymer concentration and at the polymer effective salinity ``C_SEP`` (Eq. 2.3, floored at CSE1 as in
the kernel) that maximises it over the run, and, when the slug carries surfactant, Eq. 2.11 at the slug's water and
surfactant fractions with ``mu_p0`` as the solvent viscosity -- must not exceed ``MAX_INJECTED_VISCOSITY_CP``. The
most viscosifying ``C_SEP`` is the lowest of the initial brine and the slugs for a negative SSLOPE, the highest for a
positive one: transport mixes fluids, so every cell's ``C_SEP`` lies between those values. A run above the cap is
rejected with a ``ParameterError`` naming the parameters; nothing is clipped. Microemulsion phases that hold oil
(their viscosity also depends on the oil's) are not part of the rule.
"""

from __future__ import annotations

from spflow.core.errors import ParameterError

from . import units

__all__ = ["MAX_INJECTED_VISCOSITY_CP", "polymer_salinity_range", "peak_injected_viscosity",
           "check_injected_viscosity"]

#: cap on the viscosity of an injected fluid (cP): three decades above the thesis's calibrated SP slug (~47 cP)
#: and above its polymer fit extrapolated to the CSE1 floor at 5000 ppm (~3e4 cP: a fresh-water chase after a
#: polymer slug stays admissible); beyond it the fluid is a gel, not a displacing solution (docs/forward_model.md,
#: "Injected-viscosity cap")
MAX_INJECTED_VISCOSITY_CP = 1.0e5


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


def _slug_viscosity(p: dict[str, float], sslope: float, slug, csep: float) -> float:
    """Viscosity (cP) of the aqueous fluid of ``slug`` at polymer effective salinity ``csep``: Eq. 2.1, and Eq. 2.11
    with it as the solvent when the slug carries surfactant (the kernel's aqueous-phase viscosity)."""
    from .physics.microemulsion_viscosity import microemulsion_viscosity  # numba: imported when a run is checked
    from .physics.polymer_viscosity import zero_shear_viscosity

    cp = units.polymer_ppm_to_wt_percent(slug.polymer_ppm)
    mu = float(zero_shear_viscosity(p["VIS1"], cp, csep, p["AP1"], p["AP2"], p["AP3"], sslope, p["CSE1"]))
    c3 = units.surfactant_ppm_to_volume_fraction(slug.surfactant_ppm)
    if c3 > 0.0:
        mu = float(microemulsion_viscosity(1.0 - c3, 0.0, c3, mu, p["VIS2"], p["ALPHAV1"], p["ALPHAV2"],
                                           p["ALPHAV3"], p["ALPHAV4"], p["ALPHAV5"]))
    return mu


def peak_injected_viscosity(resolved: dict[str, float], strengths: dict[str, float], schedule):
    """``(mu, slug index, C_SEP)``: the largest viscosity (cP) of an injected fluid of the run (module docstring),
    the slug it belongs to and the polymer effective salinity (meq/ml) it is reached at. The kernel's SSLOPE is
    ``polymer_salinity x SSLOPE`` (``kernel_inputs``)."""
    sslope = strengths["polymer_salinity"] * resolved["SSLOPE"]
    best = None
    for csep in polymer_salinity_range(resolved, schedule):
        for k, slug in enumerate(schedule.slugs):
            mu = _slug_viscosity(resolved, sslope, slug, csep)
            if best is None or mu > best[0]:
                best = (mu, k, csep)
    return best


def check_injected_viscosity(resolved: dict[str, float], strengths: dict[str, float], schedule) -> None:
    """Raise ``ParameterError`` if an injected fluid's viscosity (:func:`peak_injected_viscosity`) exceeds
    ``MAX_INJECTED_VISCOSITY_CP``; the message names the slug, the parameters of Eqs. 2.1-2.3 (and 2.11 for a
    surfactant slug), their values, and the allowed range of the polymer's Flory-Huggins factor."""
    mu, k, csep = peak_injected_viscosity(resolved, strengths, schedule)
    if mu <= MAX_INJECTED_VISCOSITY_CP:
        return
    from .physics.polymer_viscosity import zero_shear_viscosity  # numba: imported only for the error message

    p = resolved
    slug = schedule.slugs[k]
    s = strengths["polymer_salinity"]
    mu_p0 = float(zero_shear_viscosity(p["VIS1"], units.polymer_ppm_to_wt_percent(slug.polymer_ppm), csep, p["AP1"],
                                       p["AP2"], p["AP3"], s * p["SSLOPE"], p["CSE1"]))
    factor = mu_p0 / p["VIS1"] - 1.0
    where = (f"slug {k} ({slug.name!r}) of schedule {schedule.name!r}: {slug.polymer_ppm:g} ppm polymer, "
             f"{slug.surfactant_ppm:g} ppm surfactant, at the run's most viscosifying polymer effective salinity "
             f"C_SEP = {csep:.3g} meq/ml")
    polymer = (f"parameters AP1 = {p['AP1']:g}, AP2 = {p['AP2']:g}, AP3 = {p['AP3']:g}, SSLOPE = {p['SSLOPE']:g} "
               f"(x polymer_salinity strength {s:g}), CSE1 = {p['CSE1']:g} meq/ml, BETAP = {p['BETAP']:g} and VIS1 = "
               f"{p['VIS1']:g} cP give the polymer solution {mu_p0:.3g} cP (Eqs. 2.1-2.3: the Flory-Huggins factor "
               f"(AP1 Cp + AP2 Cp^2 + AP3 Cp^3) C_SEP^SSLOPE = {factor:.3g}; allowed range [0, "
               f"{MAX_INJECTED_VISCOSITY_CP / p['VIS1'] - 1.0:.6g}] = cap / VIS1 - 1)")
    surfactant = ""
    if slug.surfactant_ppm > 0.0:
        surfactant = (f"; with the surfactant, Eq. 2.11 with ALPHAV1-5 = {p['ALPHAV1']:g}, {p['ALPHAV2']:g}, "
                      f"{p['ALPHAV3']:g} cP, {p['ALPHAV4']:g}, {p['ALPHAV5']:g} (the term C3 ALPHAV3 "
                      f"e^(ALPHAV4 C1) grows as e^ALPHAV4) gives {mu:.3g} cP")
    raise ParameterError(
        f"injected-fluid viscosity {mu:.3g} cP is above the physical cap {MAX_INJECTED_VISCOSITY_CP:g} cP in {where}: "
        f"{polymer}{surfactant}"
    )
