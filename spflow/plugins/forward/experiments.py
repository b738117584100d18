"""The experiments of the ``forward`` stage: a bundled name (thesis Table 2.5: its schedule on the default core)
or a mapping ``{"name": str, "schedule": <slugs or schedule mapping>, "params": {forward overrides}}`` that
simulates any coreflood with its own core, rate, fluids and schedule (:meth:`spflow.study.Study.
forward_experiments` makes these). Validated before any simulation; errors name the experiment and the field.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

from spflow.core.errors import ParameterError

from .parameters import resolve_params
from .schedule import BCF_SCHEDULES, Schedule, as_schedule

__all__ = ["ForwardExperiment", "forward_experiments"]

_KEYS = ("name", "schedule", "params")


@dataclass(frozen=True)
class ForwardExperiment:
    """One simulated experiment: its name, schedule and the parameter overrides it applies on top of ``fixed``."""

    name: str
    schedule: Schedule
    params: dict[str, float]


def _one(i: int, item, fixed: Mapping) -> ForwardExperiment:
    where = f"forward experiments[{i}]"
    if isinstance(item, str):
        if item.strip().upper() not in BCF_SCHEDULES:
            raise ParameterError(f"{where} = {item!r}: unknown bundled experiment; allowed names "
                                 f"{sorted(BCF_SCHEDULES)} or a mapping {{'name', 'schedule', 'params'}}")
        return ForwardExperiment(item, as_schedule(item), {})
    if not isinstance(item, Mapping):
        raise ParameterError(f"{where} must be a bundled name or a mapping {{'name', 'schedule', 'params'}}, got "
                             f"{type(item).__name__}")
    unknown = sorted(set(item) - set(_KEYS))
    if unknown:
        raise ParameterError(f"{where}: unknown key(s) {unknown}; allowed keys {list(_KEYS)}")
    name = item.get("name")
    if not isinstance(name, str) or not name.strip():
        raise ParameterError(f"{where}: 'name' must be a non-empty string, got {name!r}")
    if "schedule" not in item:
        raise ParameterError(f"{where} ({name!r}): missing 'schedule' (slugs or {{'name', 'slugs'}})")
    try:
        schedule = as_schedule(item["schedule"])
    except ValueError as exc:
        raise ParameterError(f"{where} ({name!r}): schedule: {exc}") from None
    params = item.get("params", {})
    if not isinstance(params, Mapping):
        raise ParameterError(f"{where} ({name!r}): 'params' must be a mapping name -> value, got "
                             f"{type(params).__name__}")
    try:
        resolve_params(dict(fixed, **params))
    except ValueError as exc:
        raise ParameterError(f"{where} ({name!r}): params: {exc}") from None
    return ForwardExperiment(name, schedule, {str(k): float(v) for k, v in params.items()})


def forward_experiments(items, fixed: Mapping) -> list[ForwardExperiment]:
    """Validated experiments of the ``forward`` stage's ``experiments`` list (names must be distinct)."""
    out = [_one(i, item, fixed) for i, item in enumerate(items)]
    names = [e.name for e in out]
    dup = sorted({n for n in names if names.count(n) > 1})
    if dup:
        raise ParameterError(f"forward experiments: names {dup} occur more than once; names must be distinct")
    if not out:
        raise ParameterError("forward experiments: the list is empty; give at least one experiment")
    return out
