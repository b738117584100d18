"""Candidate effects of a gap diagnosis: strength ranges, physical ranges and fingerprint test strengths.

A candidate is a catalogue effect (:mod:`spflow.plugins.forward.effects`) whose strength ``s`` the diagnosis frees:
``s = b`` (its strength in the base model) is exactly the base model, so an effect that is off in the base
(``b = 0``) is a *missing mechanism* and one that is on is a *mis-specified strength*. Each built-in has

* a **physical range**: strengths a lab would accept as that mechanism (the decision rule's "physical strength"
  test, docs/gap.md, Method: **Decision**); for the built-ins the ranges follow the parameter sources of
  ``docs/forward_model.md``
  (e.g. IPV up to the 15 % of Table 2.4, capillary entry pressures 0.5-20 kPa for Berea, adsorption rates from
  equilibrium down to ~0.2 per PV-time, a reversible share of the polymer adsorption from 20 % -- a desorption a
  post-flush can show -- to ECLIPSE's fully reversible option);
* a **search range** for the refit, wider than the physical range so that a fit can say "weaker than physical";
* **test strengths**: the finite strengths at which fingerprints are taken (docs/gap.md, Method: **Which**: a
derivative at
  ``s = 0`` is a poor guide to a finite front shift).

Third-party effects (registered through ``spflow_register_effects``) get their registered bounds as the physical
and search range, a linear scale, and test strengths half and all the way from the base strength to the upper
bound.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from spflow.core.errors import ParameterError
from spflow.plugins.forward.effects import EffectRegistry, default_registry

from .base_model import unit_to_value, value_to_unit

__all__ = ["CandidateEffect", "MAX_EFFECTS", "PHYSICAL_RANGES", "candidates_for"]

#: the most catalogue effects a diagnosis may add to its base model (the option max_effects)
MAX_EFFECTS = 5

#: name -> (physical lower, physical upper, log scale?, test strengths when off in the base)
PHYSICAL_RANGES: dict[str, tuple[float, float, bool, tuple[float, ...]]] = {
    "inaccessible_pore_volume": (0.2, 1.0, False, (0.5, 1.0)),   # IPV 3-15 % of the pore volume
    "polymer_adsorption": (0.2, 5.0, True, (0.5, 2.0)),          # capacity x0.2-5 of Table 2.4
    "surfactant_adsorption": (0.2, 5.0, True, (0.5, 2.0)),
    "permeability_reduction": (0.2, 3.0, True, (0.5, 1.0)),      # (R_k - 1) x0.2-3
    "shear_thinning": (0.2, 1.0, False, (0.5, 1.0)),             # fraction of the Meter thinning
    "polymer_salinity": (0.3, 1.5, False, (0.5, 1.0)),           # salinity exponent x0.3-1.5
    "dispersion": (0.3, 5.0, True, (1.0, 3.0)),                  # dispersivity x0.3-5 (Pe ~ 10-150)
    "capillary_pressure": (0.1, 4.0, True, (0.25, 1.0)),         # entry pressure 0.5-20 kPa
    "kinetic_adsorption": (1.0, 300.0, True, (3.0, 30.0)),       # rate KADS/s: 1e-3 .. 3e-6 1/s
    "capillary_desaturation": (0.1, 5.0, True, (0.5, 2.0)),      # trapping parameters x0.1-5
    "reversible_polymer_adsorption": (0.2, 1.0, False, (0.5, 1.0)),  # reversible share of the polymer adsorption
}


@dataclass(frozen=True)
class CandidateEffect:
    """A freed effect strength: base value, search range and scale, physical range and fingerprint strengths."""

    name: str
    base: float
    lower: float
    upper: float
    log: bool
    physical: tuple[float, float]
    levels: tuple[float, ...]

    def value(self, v):
        """Strength at unit-box coordinate ``v`` of the search range."""
        return float(unit_to_value(np.clip(v, 0.0, 1.0), self.lower, self.upper, self.log))

    def unit(self, s) -> float:
        """Unit-box coordinate of strength ``s`` (clipped into the search range)."""
        return float(np.clip(value_to_unit(s, self.lower, self.upper, self.log), 0.0, 1.0))

    def is_physical(self, s: float, tolerance: float = 0.0) -> bool:
        """The physical-strength rule: ``s`` inside the physical range, or at most ``tolerance`` outside it in
        unit-box coordinates of the search range (the decision rule passes ``physical_tolerance`` times the
        strength's posterior sd there, docs/gap.md, Method: **Decision**)."""
        if self.physical[0] <= s <= self.physical[1]:
            return True
        v, lo, hi = self.unit(s), self.unit(self.physical[0]), self.unit(self.physical[1])
        return bool(max(lo - v, v - hi) <= tolerance)


def _candidate(name: str, base: float, registry: EffectRegistry) -> CandidateEffect:
    effect = registry[name]
    if name in PHYSICAL_RANGES:
        plo, phi, log, off_levels = PHYSICAL_RANGES[name]
        lo = max(effect.lower, plo / 10.0) if log else effect.lower
        hi = min(effect.upper, phi * 3.0)
    else:
        plo, phi, log = effect.lower, effect.upper, False
        lo, hi = effect.lower, effect.upper
        off_levels = (base + 0.5 * (hi - base), hi)
    if base == 0.0:
        levels = tuple(off_levels)
    else:  # on in the base: fingerprints at half and double the base strength, inside the effect's bounds
        lo, hi = min(lo, base), max(hi, base)
        levels = tuple(dict.fromkeys(x for x in (max(base / 2.0, lo), min(2.0 * base, hi)) if x != base))
    if not levels:
        raise ParameterError(f"candidate effect {name!r}: no test strength differs from the base strength {base:g}")
    return CandidateEffect(name, float(base), float(lo), float(hi), bool(log), (float(plo), float(phi)), levels)


def candidates_for(names: Sequence[str] | None, base_effects: Mapping[str, float],
                   registry: EffectRegistry | None = None) -> list[CandidateEffect]:
    """The candidate effects ``names`` (``None``: every registered effect) for a base model whose effect strengths
    are ``base_effects``. Unknown names raise ``ParameterError`` listing the known effects."""
    registry = registry or default_registry()
    chosen = registry.names() if names is None else list(names)
    if not chosen:
        raise ParameterError("the candidate catalogue is empty; give at least one effect name "
                             f"(known: {', '.join(registry.names())})")
    for name in chosen:
        if name not in registry:
            raise ParameterError(f"unknown candidate effect {name!r}; known effects: {', '.join(registry.names())}")
    if len(set(chosen)) != len(chosen):
        raise ParameterError(f"candidate effects must be distinct, got {chosen}")
    return [_candidate(name, float(base_effects.get(name, registry[name].default_strength)), registry)
            for name in chosen]
