"""Read and validate a study file (TOML, schema of :mod:`spflow.study.schema`): :func:`load_study`.

Everything is checked before any simulation: keys (unknown ones rejected with the allowed set), units, the data
files (they must load), values given both in the study and in the data file's metadata (they must agree within a
relative 1e-6 after unit conversion), the pore volume the file states against the core's geometry (1 %), the
schedule's total PV against the data's last PV, ranges against the forward model's bounds. A value given nowhere
is an error unless the schema marks a default acceptable; each default taken is recorded (``Study.defaults_taken``).
Every error is a :class:`StudyError` naming the study file, the experiment, the field and the allowed values.
"""

from __future__ import annotations

import json
import math
import re
import tomllib
from collections.abc import Mapping
from pathlib import Path

import numpy as np

from spflow.io import load_coreflood, read_schedule_file
from spflow.io.metadata import CORE_ATTRS, NOISE_ATTRS, core_bounds, core_unit
from spflow.io.quantities import VELOCITY_UNITS, parse_quantity, velocity_to_rate
from spflow.io.text_file import read_utf8_text
from spflow.plugins.forward.effects import default_registry
from spflow.plugins.forward.parameters import PARAMETERS, resolve_params
from spflow.plugins.forward.schedule import Schedule, as_schedule
from spflow.plugins.gap.base_model import BaseModel
from spflow.synthetic.core_volumes import ooip_ml, pore_volume_ml
from spflow.synthetic.noise_model import NoiseModel

from .defaults import DefaultTaken
from .errors import StudyError
from .experiment import Experiment
from .schema import (CORE_KEYS, EXPERIMENT_KEYS, EXPERIMENT_PARAMS, FLUID_KEYS, FROM_DATA, MEASUREMENT_KEYS,
                     MEASUREMENT_UNITS, PARAMETER_KEYS, RATE_ATTR, ROLES, TOP_KEYS, VERSION)
from .study import Study

__all__ = ["load_study", "read_study_text"]

_SPECS = {p.name: p for p in PARAMETERS}
_AGREE = 1.0e-6  # relative agreement of a value given in the study and in the data file
_PORE_VOLUME_AGREE = 0.01  # relative agreement of a stated pore volume / OOIP with the core geometry
_NAME = re.compile(r"^[A-Za-z0-9][A-Za-z0-9_.-]*$")
_SLUG_NUMBERS = ("pv", "salinity_ppm", "surfactant_ppm", "polymer_ppm")


def read_study_text(path: Path) -> str:
    """The UTF-8 text of study file ``path``; a missing, empty, binary or UTF-16 file is a :class:`StudyError`."""
    where = f"study file {str(path)!r}"
    if not path.is_file():
        raise StudyError(f"{where}: no such file")
    try:
        return read_utf8_text(path, where, "UTF-8 TOML (a study file)",
                              f"a study needs at least 'version = {VERSION}', [parameters] and one [[experiment]] "
                              "(spflow init writes a template)")
    except ValueError as exc:
        raise StudyError(str(exc)) from None


def _keys(table, allowed, where: str) -> Mapping:
    if not isinstance(table, Mapping):
        raise StudyError(f"{where} must be a table, got {type(table).__name__} {table!r}")
    unknown = sorted(set(table) - set(allowed))
    if unknown:
        raise StudyError(f"{where}: unknown key(s) {unknown}; allowed keys: {list(allowed)}")
    return table


def _quantity(value, kind: str, where: str) -> tuple[float, str]:
    """:func:`parse_quantity`, its errors as :class:`StudyError`."""
    try:
        return parse_quantity(value, kind, where)
    except ValueError as exc:
        raise StudyError(str(exc)) from None


def _agree(a: float, b: float) -> bool:
    return abs(a - b) <= _AGREE * max(abs(a), abs(b))


class _StudyReader:
    """State of one load: the study file, its directory and the defaults taken so far."""

    def __init__(self, path: Path):
        self.path = path
        self.where = f"study file {str(path)!r}"
        self.defaults: list[DefaultTaken] = []

    def fail(self, message: str):
        raise StudyError(f"{self.where}: {message}")

    # -- study-wide tables ---------------------------------------------------------------------------------------
    def parameters(self, table) -> tuple[dict[str, dict], dict[str, float]]:
        if table is None:
            self.fail("missing [parameters] table; it needs [parameters.calibrated] (name = [low, high]) and may "
                      "have [parameters.fixed]")
        _keys(table, PARAMETER_KEYS, f"{self.where}: [parameters]")
        calibrated = table.get("calibrated")
        if not isinstance(calibrated, Mapping) or not calibrated:
            self.fail("[parameters.calibrated] must list at least one calibrated parameter: name = [low, high] in "
                      "the forward model's units (`spflow list params`)")
        fixed = table.get("fixed", {})
        if not isinstance(fixed, Mapping):
            self.fail(f"[parameters.fixed] must be a table name = value, got {type(fixed).__name__}")
        per_experiment = sorted(set(fixed) & set(EXPERIMENT_PARAMS))
        if per_experiment:
            self.fail(f"[parameters.fixed] {per_experiment}: core data and rate are per experiment; give them in "
                      "[experiment.core] / rate (or the data file), not as fixed parameters")
        try:
            base = BaseModel.from_mapping({"parameters": dict(calibrated), "fixed": dict(fixed)})
        except ValueError as exc:
            self.fail(f"[parameters]: {exc}")
        space = {p.label: {"names": list(p.names), "range": [p.lower, p.upper],
                           "scale": "log" if p.log else "linear"} for p in base.parameters}
        return space, dict(base.fixed)

    def effects(self, table) -> dict[str, float]:
        registry = default_registry()
        if table is not None and not isinstance(table, Mapping):
            self.fail(f"[effects] must be a table effect = strength; known effects: {', '.join(registry.names())}")
        try:
            strengths = registry.resolve(dict(table or {}))
        except ValueError as exc:
            self.fail(f"[effects]: {exc}")
        for name in registry.names():
            if name not in (table or {}):
                self.defaults.append(DefaultTaken(None, f"effects.{name}", f"{strengths[name]:g}",
                                                  "not listed in [effects]: the effect's default strength"))
        return strengths

    # -- one experiment ------------------------------------------------------------------------------------------
    def experiment(self, index: int, table, taken_names: set, fixed: Mapping, calibrated: set) -> Experiment:
        at = f"{self.where}: [[experiment]] {index}"
        _keys(table, EXPERIMENT_KEYS, at)
        name = table.get("name")
        if not isinstance(name, str) or not _NAME.match(name):
            raise StudyError(f"{at}: field 'name' must be a name of letters, digits, '_', '.', '-' (starting with a "
                             f"letter or digit), got {name!r}")
        if name in taken_names:
            raise StudyError(f"{at}: field 'name' {name!r} is used by an earlier experiment; names must be unique")
        at = f"{self.where}: experiment {name!r}"
        role = table.get("role")
        if role not in ROLES:
            raise StudyError(f"{at}: field 'role' = {role!r}; allowed roles: {', '.join(ROLES)}")
        if role == "predict" and "data" not in table:  # a flood to predict only: everything from the study
            data, ds, attrs, data_where = None, None, {}, "its data file (none: a predict-only experiment)"
        else:
            data, ds = self._data(table.get("data"), at)
            attrs, data_where = ds.attrs, f"data file {str(data)!r}"
        sources: dict[str, str] = {}
        core = self._core(table.get("core", {}), attrs, at, data_where, sources)
        core[RATE_ATTR] = self._rate(table.get("rate"), attrs, core["core_diameter_m"], at, data_where, sources)
        self._volumes(core, attrs, at, data_where)
        schedule = self._schedule(name, table.get("schedule", FROM_DATA), attrs, at, data_where, sources)
        if ds is not None:
            self._length(schedule, ds, at, data_where)
        fluids = self._fluids(name, table.get("fluids", {}), at, fixed, calibrated, sources)
        measurement = self._measurement(name, table.get("measurement", {}), attrs, at, data_where, sources)
        return Experiment(name, role, data, core, schedule, fluids, measurement, sources, ds)

    def _data(self, value, at):
        if not isinstance(value, str) or not value.strip():
            raise StudyError(f"{at}: field 'data' must be the path of a CSV or netCDF file (relative to the study "
                             f"file), got {value!r}; only role 'predict' may go without data")
        file = Path(value)
        if not file.is_absolute():
            file = self.path.parent / file
        file = file.resolve()
        if not file.is_file():
            raise StudyError(f"{at}: field 'data': no such file {str(file)!r}")
        try:
            return file, load_coreflood(file)
        except ValueError as exc:
            raise StudyError(f"{at}: field 'data': {exc}") from None

    def _both(self, field, study_value, study_text, attr, attrs, at, data_where, sources):
        """The value of ``field`` from the study (already converted) and/or the data attr ``attr``."""
        unit = core_unit(attr)
        in_data = attr in attrs
        if study_value is None and not in_data:
            return None
        if study_value is not None and in_data:
            data_value = float(attrs[attr])
            if not _agree(study_value, data_value):
                raise StudyError(f"{at}: field {field!r} is given twice and the values disagree: study file "
                                 f"{study_text!r} (= {study_value:.10g} {unit}) vs {data_where} attr {attr!r} = "
                                 f"{data_value:.10g} {unit}; give it in one place or make them agree (relative "
                                 f"{_AGREE:g})")
            sources[field] = "study and data"
            return study_value
        sources[field] = "study" if study_value is not None else "data"
        return study_value if study_value is not None else float(attrs[attr])

    def _check_bounds(self, field, attr, value, at):
        lo, hi = core_bounds(attr)
        if not lo <= value <= hi:
            raise StudyError(f"{at}: field {field!r} = {value:.6g} {core_unit(attr)} is out of range; allowed "
                             f"[{lo:g}, {hi:g}] {core_unit(attr)} (the forward model's bounds)")

    def _core(self, table, attrs, at, data_where, sources) -> dict[str, float]:
        _keys(table, CORE_KEYS, f"{at}: [experiment.core]")
        core = {}
        for key, (attr, kind) in CORE_KEYS.items():
            field = f"core.{key}"
            given = None
            if key in table:
                given, _ = _quantity(table[key], kind, f"{at}: field {field!r}")
                self._check_bounds(field, attr, given, at)
            value = self._both(field, given, table.get(key), attr, attrs, at, data_where, sources)
            if value is None:
                raise StudyError(f"{at}: field {field!r} is missing: give it in [experiment.core] ({key} = \"<number> "
                                 f"<unit>\") or in {data_where} (attr/header {attr!r}); it has no default")
            core[attr] = value
        return core

    def _rate(self, value, attrs, diameter_m, at, data_where, sources) -> float:
        given = None
        if value is not None:
            given, unit = _quantity(value, "rate", f"{at}: field 'rate'")
            if unit in VELOCITY_UNITS:
                given = velocity_to_rate(given, unit, diameter_m)
            self._check_bounds("rate", RATE_ATTR, given, at)
        rate = self._both("rate", given, value, RATE_ATTR, attrs, at, data_where, sources)
        if rate is None:
            raise StudyError(f"{at}: field 'rate' is missing: give it as rate = \"<number> <unit>\" (ml/min, ml/h, "
                             f"ft/day ...) or in {data_where} (attr/header {RATE_ATTR!r}); it has no default")
        return rate

    def _volumes(self, core, attrs, at, data_where):
        params = {CORE_ATTRS[a]: v for a, v in core.items()}
        for attr, expected in (("pore_volume_ml", pore_volume_ml(params)), ("ooip_ml", ooip_ml(params))):
            if attr in attrs:
                stated = float(attrs[attr])
                if abs(stated - expected) > _PORE_VOLUME_AGREE * expected:
                    raise StudyError(f"{at}: {data_where} attr {attr!r} = {stated:.6g} ml disagrees with the core "
                                     f"(length, diameter, porosity, swi), which gives {expected:.6g} ml; allowed "
                                     f"within {_PORE_VOLUME_AGREE:.0%}")

    def _schedule(self, name, value, attrs, at, data_where, sources) -> Schedule:
        own = as_schedule(json.loads(attrs["schedule"])) if "schedule" in attrs else None
        if value == FROM_DATA:
            if own is None:
                raise StudyError(f"{at}: field 'schedule' = {FROM_DATA!r} but {data_where} holds no schedule; give "
                                 "the slugs inline, a TOML schedule file or a Table 2.5 name (BCF1, BCF2, BCF3)")
            sources["schedule"] = "data"
            return own
        try:
            if isinstance(value, str) and value.lower().endswith(".toml"):
                file = Path(value) if Path(value).is_absolute() else self.path.parent / value
                schedule = read_schedule_file(file)
            elif isinstance(value, list):
                schedule = as_schedule({"name": name, "slugs": value})
            else:
                schedule = as_schedule(value)
        except ValueError as exc:
            raise StudyError(f"{at}: field 'schedule': {exc}; allowed: {FROM_DATA!r}, a TOML schedule file, a "
                             "Table 2.5 name (BCF1, BCF2, BCF3) or a list of slugs {pv, salinity_ppm, "
                             "surfactant_ppm, polymer_ppm, name}") from None
        if own is not None:
            self._same_schedule(schedule, own, at, data_where)
            sources["schedule"] = "study and data"
        else:
            sources["schedule"] = "study"
        return schedule

    def _same_schedule(self, given: Schedule, own: Schedule, at, data_where):
        same = len(given.slugs) == len(own.slugs) and all(
            math.isclose(getattr(a, f), getattr(b, f), rel_tol=_AGREE, abs_tol=1e-12)
            for a, b in zip(given.slugs, own.slugs) for f in _SLUG_NUMBERS) and all(
            (a.rate_ml_min is None) == (b.rate_ml_min is None)
            and (a.rate_ml_min is None or math.isclose(a.rate_ml_min, b.rate_ml_min, rel_tol=_AGREE))
            for a, b in zip(given.slugs, own.slugs))
        if not same:
            def text(s):
                return "; ".join(f"{x.pv:g} PV {x.salinity_ppm:g}/{x.surfactant_ppm:g}/{x.polymer_ppm:g} ppm"
                                 + ("" if x.rate_ml_min is None else f" at {x.rate_ml_min:g} ml/min")
                                 for x in s.slugs)
            raise StudyError(f"{at}: field 'schedule' is given twice and the schedules disagree: study file "
                             f"[{text(given)}] vs {data_where} attr 'schedule' [{text(own)}]; use schedule = "
                             f"{FROM_DATA!r} or make them agree")

    def _length(self, schedule: Schedule, ds, at, data_where):
        ends = [np.asarray(ds[c].values, float) for c in ("pv", "pv_tube_end") if c in ds.coords]
        points = np.unique(np.concatenate([[0.0], *ends]))
        last = float(points[-1])
        total = schedule.total_pv
        spacing = float(np.max(np.diff(points))) if points.size > 1 else total
        tolerance = max(2.0 * spacing, 0.02 * total)
        if last > total * (1.0 + _AGREE) + 1e-9:
            raise StudyError(f"{at}: {data_where} runs to {last:g} PV, past the end of the schedule "
                             f"({total:g} PV): the schedule is shorter than the data; allowed data end "
                             f"[{total - tolerance:g}, {total:g}] PV")
        if total - last > tolerance:
            raise StudyError(f"{at}: the schedule ({total:g} PV) is longer than the data ({data_where} ends at "
                             f"{last:g} PV); allowed data end [{total - tolerance:g}, {total:g}] PV (two data "
                             "spacings or 2 % of the schedule); shorten the schedule to what was injected")

    def _fluids(self, name, table, at, fixed, calibrated, sources) -> dict[str, float]:
        _keys(table, FLUID_KEYS, f"{at}: [experiment.fluids]")
        fluids = {}
        for key, kind in FLUID_KEYS.items():
            field = f"fluids.{key}"
            if key in table:
                value, _ = _quantity(table[key], kind, f"{at}: field {field!r}")
                try:
                    resolve_params({key: value})
                except ValueError as exc:
                    raise StudyError(f"{at}: field {field!r}: {exc}") from None
                fluids[key] = value
                sources[field] = "study"
            elif key in calibrated:
                sources[field] = "calibrated"
            elif key in fixed:
                sources[field] = "[parameters.fixed]"
            else:
                spec = _SPECS[key]
                sources[field] = "default"
                self.defaults.append(DefaultTaken(name, field, f"{spec.default:g} {spec.unit}",
                                                  f"forward-model default: {spec.description}"))
        return fluids

    def _measurement(self, name, table, attrs, at, data_where, sources) -> NoiseModel:
        _keys(table, MEASUREMENT_KEYS, f"{at}: [experiment.measurement]")
        default = NoiseModel()
        values = {}
        noise_attr = {field: attr for attr, field in NOISE_ATTRS.items()}
        for key in MEASUREMENT_KEYS:
            field, attr, unit = f"measurement.{key}", noise_attr[key], MEASUREMENT_UNITS[key]
            given = table.get(key)
            if given is not None and (isinstance(given, bool) or not isinstance(given, (int, float))):
                raise StudyError(f"{at}: field {field!r} must be a number in {unit} (the unit the name states), got "
                                 f"{given!r}")
            if given is not None and attr in attrs and not _agree(float(given), float(attrs[attr])):
                raise StudyError(f"{at}: field {field!r} is given twice and the values disagree: study file "
                                 f"{given!r} {unit} vs {data_where} attr {attr!r} = {float(attrs[attr])!r} {unit}; "
                                 f"give it in one place or make them agree (relative {_AGREE:g})")
            if given is not None:
                values[key] = float(given)
                sources[field] = "study and data" if attr in attrs else "study"
            elif attr in attrs:
                values[key] = float(attrs[attr])
                sources[field] = "data"
            else:
                values[key] = getattr(default, key)
                sources[field] = "default"
                self.defaults.append(DefaultTaken(name, field, f"{values[key]:g} {unit}",
                                                  "the documented default measurement chain (NoiseModel)"))
        try:
            return NoiseModel(**values)
        except ValueError as exc:
            raise StudyError(f"{at}: [experiment.measurement]: {exc}") from None


def load_study(path) -> Study:
    """The validated :class:`Study` of the TOML study file ``path`` (module docstring); raises :class:`StudyError`
    before any simulation."""
    path = Path(path).resolve()
    reader = _StudyReader(path)
    text = read_study_text(path)
    try:
        table = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        reader.fail(f"invalid TOML: {exc}")
    _keys(table, TOP_KEYS, reader.where)
    if "version" not in table:
        reader.fail(f"missing 'version'; write version = {VERSION} (the schema version)")
    if table["version"] != VERSION or isinstance(table["version"], bool):
        reader.fail(f"field 'version' = {table['version']!r}; allowed versions: {VERSION}")
    space, fixed = reader.parameters(table.get("parameters"))
    effects = reader.effects(table.get("effects"))
    tables = table.get("experiment")
    if isinstance(tables, Mapping):
        reader.fail("'experiment' must be an array of tables: write [[experiment]] (double brackets) per coreflood")
    if not isinstance(tables, list) or not tables:
        reader.fail("no experiments: add at least one [[experiment]] table (name, role, data, core, rate, ...)")
    calibrated = {n for v in space.values() for n in v["names"]}
    experiments, names = [], set()
    for i, t in enumerate(tables):
        experiment = reader.experiment(i, t, names, fixed, calibrated)
        names.add(experiment.name)
        experiments.append(experiment)
    if not any(e.role == "calibration" for e in experiments):
        reader.fail(f"no experiment has role 'calibration'; at least one must (roles: {', '.join(ROLES)})")
    return Study(path, tuple(experiments), space, fixed, effects, tuple(reader.defaults))
