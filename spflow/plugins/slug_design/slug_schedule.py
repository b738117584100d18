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

A study's own flood can be the reference instead (:meth:`SlugReference.from_schedule`): its SP slug gives the
surfactant (and SP polymer) concentration, size and salinity, the polymer drive after it the polymer concentration,
size and salinity, and its first slug the water salinity; the HTDS slug is injected at the SP slug's salinity, as in
the thesis's design.
"""

from __future__ import annotations

from dataclasses import dataclass

import json
from dataclasses import asdict

import numpy as np

from spflow.core.errors import ParameterError

from spflow.plugins.forward.checks import check_number
from spflow.plugins.forward.schedule import Schedule, Slug, as_schedule

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
    """Concentrations [ppm] and reference slug sizes [PV] of Table 4.2 / Table 2.5 (see the module docstring);
    ``polymer_ppm`` is the polymer drive's, ``sp_polymer_ppm`` the SP slug's (equal in Table 4.2)."""

    surfactant_ppm: float = 6780.0
    polymer_ppm: float = 2500.0
    sp_polymer_ppm: float = 2500.0
    s_sp: float = 0.25
    s_p: float = 0.25
    water_tds_ppm: float = 9400.0
    htds_tds_ppm: float = 17500.0
    sp_tds_ppm: float = 17500.0
    p_tds_ppm: float = 9400.0

    @classmethod
    def from_schedule(cls, schedule) -> "SlugReference":
        """The reference of a flood ``schedule`` (a Schedule or its JSON mapping): its first surfactant slug (SP) and
        the first polymer-only slug after it (the polymer drive); raises ``ParameterError`` naming the schedule when
        either is missing, since the design varies both."""
        sched = as_schedule(schedule)
        where = f"slug design reference flood {sched.name or '(unnamed)'!r}"
        sp = next((i for i, s in enumerate(sched.slugs) if s.surfactant_ppm > 0.0), None)
        if sp is None:
            raise ParameterError(f"{where} has no surfactant slug; the design varies an SP slug, so the reference "
                                 "must be an SP flood (slugs: " + ", ".join(s.name for s in sched.slugs) + ")")
        drive = next((s for s in sched.slugs[sp + 1:] if s.polymer_ppm > 0.0 and s.surfactant_ppm == 0.0), None)
        if drive is None:
            raise ParameterError(f"{where} has no polymer drive (a polymer slug without surfactant) after its SP slug "
                                 f"{sched.slugs[sp].name!r}; the design varies one")
        slug = sched.slugs[sp]
        return cls(surfactant_ppm=slug.surfactant_ppm, polymer_ppm=drive.polymer_ppm,
                   sp_polymer_ppm=slug.polymer_ppm, s_sp=slug.pv, s_p=drive.pv,
                   water_tds_ppm=sched.slugs[0].salinity_ppm, htds_tds_ppm=slug.salinity_ppm,
                   sp_tds_ppm=slug.salinity_ppm, p_tds_ppm=drive.salinity_ppm)

    def to_json(self) -> str:
        """JSON text of the fields (the slug-design result's ``reference_flood`` attr)."""
        return json.dumps(asdict(self))

    @classmethod
    def from_json(cls, text: str) -> "SlugReference":
        """Inverse of :meth:`to_json`."""
        return cls(**json.loads(text))

    def describe(self) -> str:
        """One line: the concentrations and sizes of Eq. 4.10's reference slugs."""
        return (f"SP {self.s_sp:g} PV of {self.surfactant_ppm:g} ppm surfactant + {self.sp_polymer_ppm:g} ppm polymer "
                f"at {self.sp_tds_ppm:g} ppm TDS, polymer drive {self.s_p:g} PV of {self.polymer_ppm:g} ppm at "
                f"{self.p_tds_ppm:g} ppm TDS, water {self.water_tds_ppm:g} ppm, HTDS {self.htds_tds_ppm:g} ppm")


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
        Slug("SP", s_sp, r.sp_tds_ppm, r.surfactant_ppm * r.s_sp / s_sp, r.sp_polymer_ppm * r.s_sp / s_sp),
        Slug("P", s_p, r.p_tds_ppm, 0.0, r.polymer_ppm * r.s_p / s_p),
        Slug("EWF", ewf, r.water_tds_ppm),
    ), name=f"slug design s_htds={sizes['s_htds']:.3g} s_sp={s_sp:.3g} s_p={s_p:.3g}")
