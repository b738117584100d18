"""The note a diagnosis adds when it names dispersion (declared, or a member of the ambiguity set).

Dispersion is the catalogue effect that stands for front smearing of any origin: a real core's mixing, or the
numerical dispersion of the simulator that made the data. A first-order upwind scheme smears a front like a
longitudinal dispersivity ``alpha_num = dx/2 (1 + nu)`` (Lantz 1971, SPE J. 11:315; ``nu`` the front's Courant
number), and on OPM Flow's null corefloods the diagnosis with a dispersion-free base named dispersion in 3 of 3 runs
(docs/gap.md, the independent-world study). The data alone cannot tell the two origins apart, so the note states the
dispersivity the fitted strength stands for (``strength x ALPHAL1``, the effect's scale of the aqueous phase's
dispersivity, ``spflow list effects``) and what tells them apart: the data generator's own numerical dispersivity
on simulated data; on a real core, whose dispersion is never zero, a base model that calibrates a dispersivity.
"""

from __future__ import annotations

__all__ = ["dispersion_note"]


def dispersion_note(strength: float, alphal1_ft: float) -> str:
    """The note for dispersion named at ``strength`` on a model whose aqueous dispersivity ``ALPHAL1`` is
    ``alphal1_ft`` (ft)."""
    return (f"dispersion named at strength {strength:.3g}, i.e. a longitudinal dispersivity of "
            f"{strength * alphal1_ft:.3g} ft (ALPHAL1 {alphal1_ft:.3g} ft x strength). Front smearing of any origin "
            "reads as dispersion: a real core's mixing, or the numerical dispersion of the simulator that made the "
            "data (first-order upwind: about dx/2 (1 + Courant number), Lantz 1971). On simulated data compare it "
            "with that simulator's; on a real core, whose dispersion is never zero, calibrate a dispersivity in the "
            "base model (docs/gap.md, independent-world study).")
