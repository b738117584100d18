"""The base model of a gap diagnosis: what is calibrated (with ranges), what is fixed, which effects are on.

A base model is given as a mapping (a TOML file for ``spflow diagnose --base``, a dict for the ``diagnose`` stage):

.. code-block:: toml

    cells = 60                     # grid cells of every forward run
    scheme = "tvd"                 # transport scheme of every forward run: "tvd" (default) or "upwind"
    pv_step = 0.01                 # output PV step of every forward run (under the measurement chain)
    [effects]                      # base-model effect strengths; unlisted effects keep their default strength
    capillary_pressure = 0.0
    [fixed]                        # fixed forward-model parameters (UTCHEM names)
    VIS2 = 13.8
    [parameters]                   # calibrated parameters: label = [lower, upper] or a table
    ALPHAV2 = [0.0, 3.0]
    n_high = { names = ["E1C", "E2C", "E3C"], range = [1.5, 3.0] }   # one value for several UTCHEM names
    [schedules]                    # injection schedules of experiments whose files carry none
    my_flood = "BCF1"

A calibrated parameter is one number that sets one or several UTCHEM parameters (the thesis's ``n_high`` is the
high-trapping-number Corey exponent of every phase, Table 3.2). Values move in the unit box ``u in [0, 1]^p``:
``x = lo + u (hi - lo)`` (``scale = "linear"``) or ``x = lo (hi / lo)^u`` (``scale = "log"``, ``lo > 0``).
Everything is validated on construction and errors name the field and the allowed range.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from spflow.core.errors import ParameterError
from spflow.plugins.design.calibrated_parameter import CalibratedParameter, calibrated_parameter
from spflow.plugins.design.thesis_tables import TABLE_3_2
from spflow.plugins.forward.effects import default_registry
from spflow.plugins.forward.parameters import resolve_params
from spflow.plugins.forward.schedule import as_schedule

__all__ = ["CalibratedParameter", "BaseModel", "TABLE_3_2_BASE", "unit_to_value", "value_to_unit"]

_KEYS = ("cells", "scheme", "pv_step", "effects", "fixed", "parameters", "schedules")
_SCHEMES = ("tvd", "upwind")
#: default output PV step of the forward runs (fine against the 0.02 PV transducer, 0.05 PV tubes)
DEFAULT_PV_STEP = 0.01
_MAX_CELLS = 2000

#: The thesis's reduced calibration space (Table 3.2) on the default model, cells = 60 (the default base of
#: ``spflow/pipelines/gap_diagnosis.py``). ``n_high`` / ``n_low`` set the Corey exponents of all three phases.
_PHASE_GROUPS = {"E2C": ("n_high", ["E1C", "E2C", "E3C"]), "E2WC": ("n_low", ["E1WC", "E2WC", "E3WC"])}
TABLE_3_2_BASE = {
    "cells": 60,
    "parameters": dict(
        (_PHASE_GROUPS[k][0], {"names": _PHASE_GROUPS[k][1], "range": list(v)}) if k in _PHASE_GROUPS else (k, list(v))
        for k, v in TABLE_3_2.items()
    ),
}


def unit_to_value(u, lower, upper, log):
    """Physical value(s) of unit-box coordinate(s) ``u``: linear ``lo + u (hi - lo)`` or log ``lo (hi/lo)^u``."""
    u, lower, upper, log = np.broadcast_arrays(np.asarray(u, float), lower, upper, log)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        return np.where(log, lower * (upper / lower) ** u, lower + u * (upper - lower))


def value_to_unit(x, lower, upper, log):
    """Unit-box coordinate(s) of physical value(s) ``x`` (inverse of :func:`unit_to_value`)."""
    x, lower, upper, log = np.broadcast_arrays(np.asarray(x, float), lower, upper, log)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(log, np.log(np.maximum(x, 1e-300) / lower) / np.log(upper / lower),
                        (x - lower) / (upper - lower))


def _number(where: str, value) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise ParameterError(f"{where} must be a finite number, got {value!r}")
    return float(value)


@dataclass(frozen=True)
class BaseModel:
    """Calibrated parameters, fixed parameters, base effect strengths (all effects), grid cells, schedules, and
    the numerics of every forward run (transport ``scheme``, output step ``pv_step``)."""

    parameters: tuple[CalibratedParameter, ...]
    fixed: dict[str, float] = field(default_factory=dict)
    effects: dict[str, float] = field(default_factory=dict)
    cells: int = 60
    schedules: dict[str, object] = field(default_factory=dict)
    scheme: str = "tvd"
    pv_step: float = DEFAULT_PV_STEP

    @classmethod
    def from_mapping(cls, config: Mapping) -> BaseModel:
        """Validate a base-model mapping (module docstring); raises ``ParameterError`` naming the field."""
        if not isinstance(config, Mapping):
            raise ParameterError(f"the base model must be a mapping (TOML table), got {type(config).__name__}")
        unknown = sorted(set(config) - set(_KEYS))
        if unknown:
            raise ParameterError(f"base model: unknown key(s) {unknown}; allowed {list(_KEYS)}")
        cells = config.get("cells", 60)
        if isinstance(cells, bool) or not isinstance(cells, int) or not 4 <= cells <= _MAX_CELLS:
            raise ParameterError(f"base model 'cells' must be an integer in [4, {_MAX_CELLS}], got {cells!r}")
        scheme = config.get("scheme", "tvd")
        if scheme not in _SCHEMES:
            raise ParameterError(f"base model 'scheme' must be one of {list(_SCHEMES)}, got {scheme!r}")
        pv_step = _number("base model 'pv_step'", config.get("pv_step", DEFAULT_PV_STEP))
        if not 1e-4 <= pv_step <= 0.1:
            raise ParameterError(f"base model 'pv_step' must be in [0.0001, 0.1] PV, got {pv_step!r}")
        spec = config.get("parameters", {})
        if not isinstance(spec, Mapping) or not spec:
            raise ParameterError("base model [parameters] must list at least one calibrated parameter "
                                 "(label = [lower, upper])")
        parameters = tuple(calibrated_parameter(str(label), s, f"base model [parameters] {str(label)!r}")
                           for label, s in spec.items())
        taken = [n for p in parameters for n in p.names]
        dup = sorted({n for n in taken if taken.count(n) > 1})
        if dup:
            raise ParameterError(f"base model [parameters]: {dup} set by more than one calibrated parameter")
        fixed = dict(config.get("fixed", {}))
        clash = sorted(set(fixed) & set(taken))
        if clash:
            raise ParameterError(f"base model: {clash} are both [fixed] and calibrated")
        resolve_params(fixed)  # names and bounds of the fixed values
        effects = default_registry().resolve(dict(config.get("effects", {})))
        schedules = dict(config.get("schedules", {}))
        for name, sched in schedules.items():
            try:
                as_schedule(sched)
            except ValueError as exc:
                raise ParameterError(f"base model [schedules] {name!r}: {exc}") from None
        return cls(parameters, {k: float(v) for k, v in fixed.items()}, effects, int(cells), schedules, scheme,
                   pv_step)

    # -- the unit box --------------------------------------------------------------------------------------------
    @property
    def labels(self) -> list[str]:
        return [p.label for p in self.parameters]

    @property
    def lower(self) -> np.ndarray:
        return np.array([p.lower for p in self.parameters])

    @property
    def upper(self) -> np.ndarray:
        return np.array([p.upper for p in self.parameters])

    @property
    def log(self) -> np.ndarray:
        return np.array([p.log for p in self.parameters])

    def values(self, u) -> np.ndarray:
        """Physical values of the calibrated parameters at unit-box point ``u``."""
        return unit_to_value(np.clip(u, 0.0, 1.0), self.lower, self.upper, self.log)

    def unit(self, values) -> np.ndarray:
        """Unit-box point of physical values (clipped into the box)."""
        return np.clip(value_to_unit(values, self.lower, self.upper, self.log), 0.0, 1.0)

    def default_unit(self) -> np.ndarray:
        """The forward model's defaults (the thesis's calibrated set) as a unit-box point, clipped into the box."""
        return self.unit([p.default for p in self.parameters])

    def forward_params(self, values) -> dict[str, float]:
        """UTCHEM parameter dict of the fixed values plus the calibrated ``values`` (physical units)."""
        out = dict(self.fixed)
        for p, v in zip(self.parameters, np.atleast_1d(values)):
            for name in p.names:
                out[name] = float(v)
        return out
