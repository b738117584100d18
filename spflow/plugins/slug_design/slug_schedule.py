"""Slug sizes -> injection schedule with constant chemical mass (thesis §4.7, Table 4.2, Eq. 4.10).

The design variables are the slug sizes x = (s_htds, s_sp, s_p), each in [0.1, 1.0] PV (Table 4.2). The sequence is
IWF -> HTDS -> SP -> P -> EWF (§4.7) with

* IWF fixed at 1.0 PV of 9 400 ppm brine (it brings the core to S_or ≈ 0.4 before the chemical flood starts);
* HTDS: s_htds PV of 17 500 ppm brine (salt concentration constant, Table 4.2);
* SP: s_sp PV at 17 500 ppm TDS with surfactant c_surf = c_surf_ref · s_sp_ref / s_sp and polymer
  c_poly = c_poly_ref · s_sp_ref / s_sp (Eq. 4.10: the injected chemical mass c · s is that of the reference slug);
* P: s_p PV at 9 400 ppm TDS with polymer c_poly = c_poly_ref · s_p_ref / s_p (Eq. 4.10);
* EWF: 9 400 ppm brine up to ``total_pv``: its length total_pv - (1 + s_htds + s_sp + s_p) is whatever is left, so
  every design ends at the same total injected PV and therefore, through the scale-up, at the same project time.

Reference concentrations are those of the corefloods BCF2/BCF3 (Table 2.5): surfactant 6 780 ppm (Table 4.2's
"0.68 %") and polymer 2 500 ppm. Table 4.2 prints the polymer reference as 25 000 ppm, ten times every polymer
concentration of Table 2.5; we take that for a typo and use 2 500 ppm. Reference slugs s_sp_ref = s_p_ref = 0.25 PV
(Table 4.2).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from spflow.plugins.forward.checks import check_number
from spflow.plugins.forward.schedule import Schedule, Slug

__all__ = ["DESIGN_VARIABLES", "SLUG_RANGE", "IWF_PV", "SlugReference", "REFERENCE", "slug_schedule",
           "design_bounds", "minimum_total_pv"]

#: Names of the design variables, in the order of a design row.
DESIGN_VARIABLES = ("s_htds", "s_sp", "s_p")
#: Range of every slug size [PV] (Table 4.2).
SLUG_RANGE = (0.1, 1.0)
#: Fixed initial water flood [PV] (§4.7).
IWF_PV = 1.0


@dataclass(frozen=True)
class SlugReference:
    """Concentrations [ppm] and reference slug sizes [PV] of Table 4.2 / Table 2.5 (see the module docstring)."""

    surfactant_ppm: float = 6780.0
    polymer_ppm: float = 2500.0
    s_sp: float = 0.25
    s_p: float = 0.25
    water_tds_ppm: float = 9400.0
    htds_tds_ppm: float = 17500.0
    sp_tds_ppm: float = 17500.0
    p_tds_ppm: float = 9400.0


#: The reference used throughout (polymer 2 500 ppm, not Table 4.2's 25 000).
REFERENCE = SlugReference()


def design_bounds() -> np.ndarray:
    """(3, 2) lower/upper bounds [PV] of (s_htds, s_sp, s_p)."""
    return np.array([SLUG_RANGE] * len(DESIGN_VARIABLES), dtype=float)


def minimum_total_pv() -> float:
    """Bound on ``total_pv``: IWF plus three slugs at their upper bound; ``total_pv`` must exceed it (EWF > 0)."""
    return IWF_PV + len(DESIGN_VARIABLES) * SLUG_RANGE[1]


def slug_schedule(s_htds: float, s_sp: float, s_p: float, *, total_pv: float,
                  reference: SlugReference = REFERENCE) -> Schedule:
    """The schedule IWF -> HTDS -> SP -> P -> EWF of one design, ending at ``total_pv`` (Eq. 4.10 concentrations).

    Raises ``ParameterError`` naming the slug size outside [0.1, 1.0] PV, or ``total_pv`` unless it exceeds
    :func:`minimum_total_pv` (4.0 PV), so that every admissible design keeps an EWF.
    """
    sizes = {name: check_number(f"slug size {name!r} [PV]", value, *SLUG_RANGE)
             for name, value in zip(DESIGN_VARIABLES, (s_htds, s_sp, s_p))}
    total = check_number("total_pv [PV]", total_pv, minimum_total_pv(), 1.0e3, lower_open=True)
    ewf = total - IWF_PV - sum(sizes.values())
    r = reference
    s_sp, s_p = sizes["s_sp"], sizes["s_p"]
    return Schedule((
        Slug("IWF", IWF_PV, r.water_tds_ppm),
        Slug("HTDS", sizes["s_htds"], r.htds_tds_ppm),
        Slug("SP", s_sp, r.sp_tds_ppm, r.surfactant_ppm * r.s_sp / s_sp, r.polymer_ppm * r.s_sp / s_sp),
        Slug("P", s_p, r.p_tds_ppm, 0.0, r.polymer_ppm * r.s_p / s_p),
        Slug("EWF", ewf, r.water_tds_ppm),
    ), name=f"slug design s_htds={sizes['s_htds']:.3g} s_sp={s_sp:.3g} s_p={s_p:.3g}")
