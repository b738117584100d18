"""The effect catalogue: mechanisms a "base" forward model may lack, each switchable with a strength.

A strength of 0 removes the mechanism; the default strength is the full (calibrated) model. Built-in effects are
applied by the forward model itself (as parameter scalings or kernel strength scalars, see
``kernel_inputs.py``); third-party effects that cannot enter the compiled kernel provide pure callables
``transform_params(params, strength) -> params`` (applied before the run) and/or
``transform_output(ds, strength) -> ds`` (applied to the returned Dataset).

Built-ins (meaning of the strength ``s``):

============================= ========= =================================================================
name                          default   strength
============================= ========= =================================================================
inaccessible_pore_volume      1         IPV fraction scale: EPHI = 1 - s (1 - EPHI) for EPHI3 and EPHI4
polymer_adsorption            1         Langmuir capacity scale: AD41, AD42 -> s AD41, s AD42 (Eq. 2.16)
surfactant_adsorption         1         Langmuir capacity scale: AD31, AD32 -> s AD31, s AD32 (Eq. 2.16)
permeability_reduction        1         R_k -> 1 + s (R_k - 1) (Eq. 2.7)
shear_thinning                1         mu_p -> mu_p0 - s (mu_p0 - mu_Meter) (Eq. 2.4), s in [0, 1]
polymer_salinity              1         salinity exponent scale: C_SEP^(s SSLOPE) in Eqs. 2.1-2.2 and 2.8
dispersion                    1         dispersivity and diffusion scale: ALPHALl, DMOL -> s ALPHALl, s DMOL
capillary_pressure            0         entry-pressure scale: CPC0 -> s CPC0 (Eq. 1.8)
kinetic_adsorption            0         non-equilibrium degree: rate KADS / s toward the Langmuir value;
                                        s = 0 is instantaneous (equilibrium) adsorption
capillary_desaturation        1         trapping-parameter scale: T11, T22, T33 -> s T (Eq. 2.12); s = 0
                                        keeps the low-Nc residuals, end points and exponents
reversible_polymer_adsorption 0         irreversible -> reversible blend of the polymer adsorption: reversible
                                        fraction f = ADSREV4 + s (1 - ADSREV4); s = 0 keeps ADSREV4 (default
                                        0: irreversible in concentration, UTCHEM), s = 1 is fully reversible
============================= ========= =================================================================
"""

from __future__ import annotations

import difflib
import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass

from spflow.core.errors import ParameterError, PluginError

__all__ = ["Effect", "EffectRegistry", "BUILTIN_EFFECTS", "register_builtin_effects", "default_registry"]


@dataclass(frozen=True)
class Effect:
    """A switchable mechanism of the forward model.

    ``transform_params``/``transform_output`` are only for third-party effects (built-ins are handled inside the
    forward model); both must be pure functions of their arguments.
    """

    name: str
    description: str
    default_strength: float
    lower: float = 0.0
    upper: float = 1.0
    transform_params: Callable | None = None
    transform_output: Callable | None = None

    def __post_init__(self):
        if not isinstance(self.name, str) or not self.name.isidentifier():
            raise PluginError(f"effect name must be an identifier string, got {self.name!r}")
        if not (math.isfinite(self.lower) and math.isfinite(self.upper) and self.lower <= self.upper):
            raise PluginError(f"effect {self.name!r}: strength bounds [{self.lower}, {self.upper}] are invalid")
        if not self.lower <= self.default_strength <= self.upper:
            raise PluginError(
                f"effect {self.name!r}: default strength {self.default_strength} outside [{self.lower}, {self.upper}]"
            )


#: The forward model's own effects (strength semantics in the module docstring).
BUILTIN_EFFECTS: tuple[Effect, ...] = (
    Effect("inaccessible_pore_volume", "polymer/surfactant inaccessible pore volume (EPHI4/EPHI3)", 1.0),
    Effect("polymer_adsorption", "Langmuir polymer adsorption, irreversible in concentration", 1.0, 0.0, 10.0),
    Effect("surfactant_adsorption", "Langmuir surfactant adsorption, irreversible in concentration", 1.0, 0.0, 10.0),
    Effect("permeability_reduction", "polymer permeability reduction / residual resistance (R_k)", 1.0, 0.0, 5.0),
    Effect("shear_thinning", "Meter shear thinning of the polymer solution at the in-situ shear rate", 1.0),
    Effect("polymer_salinity", "salinity dependence of polymer viscosity (C_SEP^SSLOPE)", 1.0, 0.0, 2.0),
    Effect("dispersion", "longitudinal physical dispersion per phase", 1.0, 0.0, 10.0),
    Effect("capillary_pressure", "Brooks-Corey capillary pressure scaled with IFT", 0.0, 0.0, 10.0),
    Effect("kinetic_adsorption", "first-order (non-equilibrium) adsorption toward the Langmuir value",
           0.0, 0.0, 1.0e3),
    Effect("capillary_desaturation", "trapping-number dependence of residuals and rel-perms", 1.0, 0.0, 10.0),
    Effect("reversible_polymer_adsorption", "desorption of adsorbed polymer as the concentration falls "
           "(irreversible -> reversible Langmuir adsorption)", 0.0, 0.0, 1.0),
)

BUILTIN_NAMES = frozenset(e.name for e in BUILTIN_EFFECTS)


def register_builtin_effects(register: Callable[[Effect], None]) -> None:
    """Call ``register(effect)`` for every built-in effect (wired by the lead to ``spflow_register_effects``)."""
    for effect in BUILTIN_EFFECTS:
        register(effect)


class EffectRegistry:
    """Known effects by name; resolves user ``effects=`` mappings to ``{name: strength}`` for every effect."""

    def __init__(self, effects=()):
        self._effects: dict[str, Effect] = {}
        for effect in effects:
            self.register(effect)

    def register(self, effect: Effect) -> None:
        if not isinstance(effect, Effect):
            raise PluginError(f"expected an Effect, got {type(effect).__name__}")
        if effect.name in self._effects:
            raise PluginError(f"effect {effect.name!r} is already registered")
        self._effects[effect.name] = effect

    def __contains__(self, name) -> bool:
        return name in self._effects

    def __getitem__(self, name: str) -> Effect:
        return self._effects[name]

    def names(self) -> list[str]:
        return list(self._effects)

    def resolve(self, effects: Mapping[str, float] | None) -> dict[str, float]:
        """Every registered effect's strength: defaults overridden by ``effects``; unknown names or strengths out
        of bounds raise ``ParameterError`` (a ``ValueError``)."""
        if effects is not None and not isinstance(effects, Mapping):
            raise ParameterError(f"effects must be a mapping name -> strength, got {type(effects).__name__}")
        strengths = {name: e.default_strength for name, e in self._effects.items()}
        for name, value in (effects or {}).items():
            if name not in self._effects:
                close = difflib.get_close_matches(str(name), self.names(), n=2)
                hint = f" (did you mean {', '.join(close)}?)" if close else ""
                raise ParameterError(f"unknown effect {name!r}{hint}; known effects: {', '.join(self.names())}")
            e = self._effects[name]
            bad = isinstance(value, bool)
            try:
                x = float(value)
            except (TypeError, ValueError):
                bad = True
            if bad or not math.isfinite(x) or not e.lower <= x <= e.upper:
                raise ParameterError(
                    f"effect {name!r} strength {value!r} is out of range; allowed [{e.lower:g}, {e.upper:g}]"
                )
            strengths[name] = x
        return strengths


def default_registry() -> EffectRegistry:
    """A registry of the built-ins plus every effect contributed through the ``spflow_register_effects`` hook."""
    from spflow.core.plugins import get_registry  # deferred: the plugin registry imports this module

    registry = EffectRegistry(BUILTIN_EFFECTS)
    for name, effect in get_registry().effects.items():
        if name not in registry and isinstance(effect, Effect):
            registry.register(effect)
    return registry
