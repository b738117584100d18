"""Injection schedules: slugs of brine, surfactant and polymer (thesis Table 2.5).

A :class:`Schedule` is a named sequence of :class:`Slug` s injected one after the other, each at its own rate
``rate_ml_min`` (ml/min; ``None``, the default, is the run's QINJ). Injected pore volumes stay the time axis of every
output whatever the rates: a rate step changes the Darcy velocity (pressure drop, shear rate, trapping number,
capillary diffusion, the time per PV seen by kinetic adsorption), not the PV at which a slug ends. Concentrations are user-facing lab units (ppm); :meth:`Schedule.kernel_arrays` converts them once, through
:mod:`spflow.plugins.forward.units`, to the kernel's units (meq/ml, volume fraction, wt %).

Validation happens before any work and names the slug (index and name) and the field at fault.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from spflow.core.errors import ParameterError

from . import units
from .checks import check_number
from .parameters import PARAMETERS

__all__ = ["Slug", "Schedule", "BCF_SCHEDULES", "as_schedule"]

_MAX_PPM = 1.0e6
#: allowed per-slug rates: the bounds of QINJ (ml/min)
_RATE_BOUNDS = next((spec.lower, spec.upper) for spec in PARAMETERS if spec.name == "QINJ")


@dataclass(frozen=True)
class Slug:
    """One injected slug: size in pore volumes, concentrations in ppm (TDS, surfactant, polymer) and the injection
    rate in ml/min (``None``: the run's QINJ)."""

    name: str
    pv: float
    salinity_ppm: float
    surfactant_ppm: float = 0.0
    polymer_ppm: float = 0.0
    rate_ml_min: float | None = None

    def validated(self, index: int) -> Slug:
        """A copy with float fields, or ``ParameterError`` naming slug ``index``/``name`` and the field."""
        where = f"slug {index} ({self.name!r})"
        if not isinstance(self.name, str) or not self.name:
            raise ParameterError(f"slug {index}: field 'name' must be a non-empty string, got {self.name!r}")
        return Slug(
            name=self.name,
            pv=check_number(f"{where}: field 'pv'", self.pv, 0.0, math.inf, lower_open=True),
            salinity_ppm=check_number(f"{where}: field 'salinity_ppm'", self.salinity_ppm, 0.0, _MAX_PPM),
            surfactant_ppm=check_number(f"{where}: field 'surfactant_ppm'", self.surfactant_ppm, 0.0, _MAX_PPM),
            polymer_ppm=check_number(f"{where}: field 'polymer_ppm'", self.polymer_ppm, 0.0, _MAX_PPM),
            rate_ml_min=None if self.rate_ml_min is None else check_number(
                f"{where}: field 'rate_ml_min' (ml/min)", self.rate_ml_min, *_RATE_BOUNDS),
        )


@dataclass(frozen=True)
class Schedule:
    """A named, non-empty sequence of slugs (validated on construction)."""

    slugs: tuple[Slug, ...]
    name: str = "custom"

    def __post_init__(self):
        if not isinstance(self.slugs, (tuple, list)) or len(self.slugs) == 0:
            raise ParameterError(f"schedule {self.name!r} is empty: it needs at least one slug with pv > 0")
        checked = []
        for i, slug in enumerate(self.slugs):
            if not isinstance(slug, Slug):
                raise ParameterError(f"slug {i} of schedule {self.name!r} must be a Slug, got {type(slug).__name__}")
            checked.append(slug.validated(i))
        object.__setattr__(self, "slugs", tuple(checked))

    @property
    def total_pv(self) -> float:
        """Total injected pore volumes."""
        return float(math.fsum(s.pv for s in self.slugs))

    def kernel_arrays(self) -> dict[str, np.ndarray]:
        """Per-slug arrays in kernel units: cumulative end PV, surfactant vol. frac., polymer wt %, anions and
        divalent cations in meq/ml."""
        ends = np.cumsum([s.pv for s in self.slugs], dtype=np.float64)
        return {
            "end_pv": ends,
            "c3": np.array([units.surfactant_ppm_to_volume_fraction(s.surfactant_ppm) for s in self.slugs]),
            "c4": np.array([units.polymer_ppm_to_wt_percent(s.polymer_ppm) for s in self.slugs]),
            "c5": np.array([units.tds_ppm_to_anions(s.salinity_ppm) for s in self.slugs]),
            "c6": np.array([units.tds_ppm_to_divalent(s.salinity_ppm) for s in self.slugs]),
        }

    def rates_ml_min(self, qinj: float) -> np.ndarray:
        """Per-slug injection rates (ml/min): each slug's ``rate_ml_min``, or ``qinj`` (the run's QINJ) where unset."""
        return np.array([qinj if s.rate_ml_min is None else s.rate_ml_min for s in self.slugs], dtype=np.float64)

    def rate_steps_pv(self) -> np.ndarray:
        """Cumulative PV of every slug end after which the injection rate changes (``rate_ml_min`` differs from the
        next slug's; unset against set counts as a change, as the run's QINJ may differ). Δp jumps there."""
        ends = np.cumsum([s.pv for s in self.slugs], dtype=np.float64)
        return np.array([e for e, a, b in zip(ends, self.slugs, self.slugs[1:]) if a.rate_ml_min != b.rate_ml_min],
                        dtype=np.float64)

    @property
    def has_rates(self) -> bool:
        """True when some slug sets its own ``rate_ml_min``."""
        return any(s.rate_ml_min is not None for s in self.slugs)


def _bcf(name, iwf, htds, sp_pv, sp_tds, poly_ppm, p_pv, ewf):
    slugs = [Slug("IWF", iwf, 9400.0)]
    if htds:
        slugs.append(Slug("HTDS", htds, 17500.0))
    slugs += [
        Slug("SP", sp_pv, sp_tds, 6780.0, poly_ppm),
        Slug("P", p_pv, 9400.0, 0.0, poly_ppm),
        Slug("EWF", ewf, 9400.0),
    ]
    return Schedule(tuple(slugs), name)


#: The three Berea corefloods of thesis Table 2.5 (BCF1 has no HTDS slug).
BCF_SCHEDULES: dict[str, Schedule] = {
    "BCF1": _bcf("BCF1", 1.45, None, 0.50, 9400.0, 3300.0, 1.01, 1.27),
    "BCF2": _bcf("BCF2", 1.60, 1.0, 0.25, 17500.0, 2500.0, 0.50, 1.59),
    "BCF3": _bcf("BCF3", 1.60, 0.25, 0.25, 17500.0, 2500.0, 0.51, 1.49),
}

_SLUG_FIELDS = ("name", "pv", "salinity_ppm", "surfactant_ppm", "polymer_ppm", "rate_ml_min")


def _slug_from_mapping(i: int, m: Mapping) -> Slug:
    unknown = sorted(set(m) - set(_SLUG_FIELDS))
    if unknown:
        raise ParameterError(f"slug {i}: unknown field(s) {unknown}; allowed fields {list(_SLUG_FIELDS)}")
    for required in ("pv", "salinity_ppm"):
        if required not in m:
            raise ParameterError(f"slug {i}: missing field {required!r}; required fields ['pv', 'salinity_ppm']")
    return Slug(
        name=m.get("name", f"slug{i}"),
        pv=m["pv"],
        salinity_ppm=m["salinity_ppm"],
        surfactant_ppm=m.get("surfactant_ppm", 0.0),
        polymer_ppm=m.get("polymer_ppm", 0.0),
        rate_ml_min=m.get("rate_ml_min"),
    )


def as_schedule(obj) -> Schedule:
    """A :class:`Schedule` from a Table 2.5 name (``"BCF1"``..), a Schedule, a list of Slug/mappings, or a mapping
    ``{"name": ..., "slugs": [...]}``. Raises ``ParameterError`` (a ``ValueError``) on anything invalid."""
    if isinstance(obj, Schedule):
        return obj
    if isinstance(obj, str):
        key = obj.strip().upper()
        if key not in BCF_SCHEDULES:
            raise ParameterError(f"unknown schedule name {obj!r}; known: {', '.join(BCF_SCHEDULES)}")
        return BCF_SCHEDULES[key]
    name = "custom"
    slugs = obj
    if isinstance(obj, Mapping):
        if "slugs" not in obj:
            raise ParameterError("a schedule mapping needs a 'slugs' list (and optionally a 'name')")
        name = str(obj.get("name", "custom"))
        slugs = obj["slugs"]
    if not isinstance(slugs, Sequence) or isinstance(slugs, (str, bytes)):
        raise ParameterError(f"schedule must be a name, a Schedule or a list of slugs, got {type(obj).__name__}")
    if len(slugs) == 0:
        raise ParameterError(f"schedule {name!r} is empty: it needs at least one slug with pv > 0")
    built = []
    for i, s in enumerate(slugs):
        if isinstance(s, Slug):
            built.append(s)
        elif isinstance(s, Mapping):
            built.append(_slug_from_mapping(i, s))
        else:
            raise ParameterError(f"slug {i} must be a Slug or a mapping, got {type(s).__name__}")
    return Schedule(tuple(built), name)
