"""The measurement-noise specification of a lab coreflood (:class:`NoiseModel`).

One frozen dataclass holds every number of the measurement model (see ``docs/data.md``), with explicit units:

* pressure transducer (:mod:`spflow.synthetic.transducer`): reading ``dp (1 + e_k) + offset + drift * pv``, where
  ``e_k`` is a stationary AR(1) sequence of standard deviation ``pressure_relative`` and lag-1 correlation
  ``pressure_ar1``, sampled every ``pressure_interval_pv``;
* fraction collector (:mod:`spflow.synthetic.fraction_collector`): tubes of ``tube_pv`` pore volumes; the oil
  column of each tube is read with an independent error uniform on +-``oil_resolution_ml`` / 2; effluent
  concentrations carry an independent relative Gaussian error ``concentration_relative``;
* outlet lines (:mod:`spflow.synthetic.dead_volume`): ``dead_volume_ml`` between the core outlet and the collector.
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Mapping
from dataclasses import asdict, dataclass, fields

__all__ = ["NoiseModel"]

#: field -> (unit, lower, upper, lower bound open?, upper bound open?)
_SPEC = {
    "pressure_relative": ("1", 0.0, 1.0, False, False),
    "pressure_ar1": ("1", 0.0, 1.0, False, True),
    "pressure_offset_pa": ("Pa", -math.inf, math.inf, True, True),
    "pressure_drift_pa_per_pv": ("Pa/PV", -math.inf, math.inf, True, True),
    "pressure_interval_pv": ("PV", 0.0, 1.0, True, False),
    "tube_pv": ("PV", 0.0, 1.0, True, False),
    "oil_resolution_ml": ("ml", 0.0, 100.0, False, False),
    "concentration_relative": ("1", 0.0, 1.0, False, False),
    "dead_volume_ml": ("ml", 0.0, 1.0e4, False, False),
}


def _describe(lo: float, hi: float, lo_open: bool, hi_open: bool, unit: str) -> str:
    return f"{'(' if lo_open else '['}{lo:g}, {hi:g}{')' if hi_open else ']'} {unit}"


@dataclass(frozen=True)
class NoiseModel:
    """Measurement model of a lab coreflood; defaults describe a typical Berea-core SP flood rig.

    Attributes (units):
        pressure_relative: standard deviation of the relative pressure-transducer noise (-), default 0.02.
        pressure_ar1: lag-1 autocorrelation of that noise between successive samples (-), in [0, 1), default 0.8.
        pressure_offset_pa: zero offset of the transducer (Pa), default 150.
        pressure_drift_pa_per_pv: linear drift of the zero (Pa per injected PV), default 40.
        pressure_interval_pv: transducer sampling interval (PV), default 0.02.
        tube_pv: volume of one effluent tube (PV), default 0.05.
        oil_resolution_ml: graduation of the tube scale (ml); reading error uniform on +-half of it, default 0.1.
        concentration_relative: relative standard deviation of effluent-concentration assays (-), default 0.03.
        dead_volume_ml: outlet-line volume between core and collector (ml), default 2.0.
    """

    pressure_relative: float = 0.02
    pressure_ar1: float = 0.8
    pressure_offset_pa: float = 150.0
    pressure_drift_pa_per_pv: float = 40.0
    pressure_interval_pv: float = 0.02
    tube_pv: float = 0.05
    oil_resolution_ml: float = 0.1
    concentration_relative: float = 0.03
    dead_volume_ml: float = 2.0

    def __post_init__(self):
        for name, (unit, lo, hi, lo_open, hi_open) in _SPEC.items():
            value = getattr(self, name)
            allowed = _describe(lo, hi, lo_open, hi_open, unit)
            if isinstance(value, bool) or not isinstance(value, numbers.Real):
                raise ValueError(f"NoiseModel field {name!r} must be a number, got {value!r}; allowed {allowed}")
            x = float(value)
            inside = (x > lo if lo_open else x >= lo) and (x < hi if hi_open else x <= hi)
            if not math.isfinite(x) or not inside:
                raise ValueError(f"NoiseModel field {name!r} = {value!r} is out of range; allowed {allowed}")
            object.__setattr__(self, name, x)

    @classmethod
    def exact(cls, **overrides) -> NoiseModel:
        """No random error, offset, drift or dead volume (sampling and tube sizes as given or default)."""
        base = dict(pressure_relative=0.0, pressure_ar1=0.0, pressure_offset_pa=0.0, pressure_drift_pa_per_pv=0.0,
                    oil_resolution_ml=0.0, concentration_relative=0.0, dead_volume_ml=0.0)
        return cls(**(base | overrides))

    @classmethod
    def random_only(cls, **overrides) -> NoiseModel:
        """The default random errors without offset, drift or dead volume: the data of a "clean" synthetic twin."""
        return cls(**(dict(pressure_offset_pa=0.0, pressure_drift_pa_per_pv=0.0, dead_volume_ml=0.0) | overrides))

    @classmethod
    def from_mapping(cls, values: Mapping) -> NoiseModel:
        """Build from ``{field: value}`` (e.g. a TOML table); unknown fields raise ``ValueError``."""
        known = {f.name for f in fields(cls)}
        unknown = sorted(set(values) - known)
        if unknown:
            raise ValueError(f"unknown NoiseModel field(s) {unknown}; allowed fields {sorted(known)}")
        return cls(**dict(values))

    def to_attrs(self) -> dict[str, float | str]:
        """``noise_<field>`` attributes (and their units as ``noise_<field>_units``) for a Dataset."""
        attrs: dict[str, float | str] = {}
        for name, value in asdict(self).items():
            attrs[f"noise_{name}"] = value
            attrs[f"noise_{name}_units"] = _SPEC[name][0]
        return attrs
