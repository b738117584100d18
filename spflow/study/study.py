"""A study (:class:`Study`): the corefloods of one investigation with their roles, the parameter space, the base
model's effects and every default taken. Built by :func:`spflow.study.load_study`."""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path

from spflow.io.metadata import core_unit
from spflow.plugins.forward.parameters import PARAMETERS

from .defaults import DefaultTaken
from .errors import StudyError
from .experiment import Experiment
from .schema import ROLES, VERSION

__all__ = ["Study"]

_SPECS = {p.name: p for p in PARAMETERS}


def _unit(names) -> str:
    unit = _SPECS[names[0]].unit
    return "" if unit == "-" else f" {unit}"


@dataclass(frozen=True)
class Study:
    """A validated study.

    Attributes:
        path: the study file (``None`` if built in memory).
        experiments: the experiments in file order.
        parameter_space: calibrated parameters, ``{label: {"names": [...], "range": [low, high], "scale": ...}}``
            (the ``[parameters]`` table of a gap-diagnosis base model, :mod:`spflow.plugins.gap.base_model`, and the
            ``parameter_space`` stage's ``ranges``: the space the chapter-3/4 pipelines calibrate).
        fixed: study-wide fixed forward-model parameters ``{name: value}``.
        effects: the base model's strength of every registered effect.
        defaults_taken: every default the study took, in order.
    """

    path: Path | None
    experiments: tuple[Experiment, ...]
    parameter_space: dict[str, dict]
    fixed: dict[str, float]
    effects: dict[str, float]
    defaults_taken: tuple[DefaultTaken, ...]

    def by_role(self, role: str) -> list[Experiment]:
        """The experiments of ``role`` (``calibration``, ``heldout``, ``predict``), in file order."""
        if role not in ROLES:
            raise StudyError(f"unknown role {role!r}; allowed roles: {', '.join(ROLES)}")
        return [e for e in self.experiments if e.role == role]

    def experiment(self, name: str) -> Experiment:
        """The experiment called ``name``."""
        for e in self.experiments:
            if e.name == name:
                return e
        raise StudyError(f"no experiment {name!r} in the study; it has {[e.name for e in self.experiments]}")

    @property
    def names(self) -> list[str]:
        """Experiment names in file order."""
        return [e.name for e in self.experiments]

    def forward_experiments(self, roles: Iterable[str] | None = None) -> list[dict]:
        """The ``forward`` stage's ``experiments`` for the experiments of ``roles`` (all if ``None``):
        ``[{"name", "schedule", "params"}]``, each simulated with its own core, rate, fluids and schedule."""
        wanted = ROLES if roles is None else tuple(roles)
        for role in wanted:
            if role not in ROLES:
                raise StudyError(f"unknown role {role!r}; allowed roles: {', '.join(ROLES)}")
        return [e.forward_experiment() for e in self.experiments if e.role in wanted]

    def base_model_config(self) -> dict:
        """``{"parameters", "fixed", "effects"}`` — a gap-diagnosis base model (add ``cells``)."""
        return {"parameters": {k: dict(v) for k, v in self.parameter_space.items()}, "fixed": dict(self.fixed),
                "effects": dict(self.effects)}

    def describe(self) -> list[str]:
        """Text lines summarising the study and listing every default taken (for ``spflow check`` and reports)."""
        where = str(self.path) if self.path is not None else "(in memory)"
        roles = "; ".join(f"{role}: {', '.join(e.name for e in self.by_role(role)) or '-'}" for role in ROLES)
        lines = [f"study {where} (version {VERSION}): {len(self.experiments)} experiment(s) — {roles}"]
        space = ", ".join(f"{label} [{v['range'][0]:g}, {v['range'][1]:g}]{_unit(v['names'])}"
                          + (f" ({'/'.join(v['names'])})" if v["names"] != [label] else "")
                          + (" log" if v.get("scale") == "log" else "")
                          for label, v in self.parameter_space.items())
        lines.append(f"calibrated parameters ({len(self.parameter_space)}): {space}")
        lines.append("fixed parameters: " + (", ".join(f"{k} = {v:g}{_unit([k])}" for k, v in self.fixed.items())
                                             or "none (model defaults)"))
        lines.append("base-model effects: " + ", ".join(f"{k} = {v:g}" for k, v in self.effects.items()))
        for e in self.experiments:
            lines.append(f"experiment {e.name!r} ({e.role}): data {e.data or 'none (predicted only)'}")
            core = ", ".join(f"{attr} = {v:.6g} {core_unit(attr)}" for attr, v in e.core.items())
            lines.append(f"  core: {core}; pore volume {e.pore_volume_ml():.4g} ml")
            slugs = ", ".join(f"{s.name} {s.pv:g} PV ({s.salinity_ppm:g}/{s.surfactant_ppm:g}/{s.polymer_ppm:g} ppm "
                              "TDS/surf./poly." + ("" if s.rate_ml_min is None else f", {s.rate_ml_min:g} ml/min")
                              + ")" for s in e.schedule.slugs)
            lines.append(f"  schedule {e.schedule.name!r}: {slugs}; total {e.schedule.total_pv:g} PV")
            if e.fluids:
                lines.append("  fluids: " + ", ".join(f"{k} = {v:g}{_unit([k])}" for k, v in e.fluids.items()))
            m = e.measurement
            lines.append(f"  measurement: transducer {m.pressure_relative:g} relative (AR(1) {m.pressure_ar1:g}), "
                         f"offset {m.pressure_offset_pa:g} Pa, drift {m.pressure_drift_pa_per_pv:g} Pa/PV, every "
                         f"{m.pressure_interval_pv:g} PV; tubes {m.tube_pv:g} PV read to {m.oil_resolution_ml:g} ml; "
                         f"assays {m.concentration_relative:g} relative; dead volume {m.dead_volume_ml:g} ml")
            by_source: dict[str, list[str]] = {}
            for key, source in e.sources.items():
                by_source.setdefault(source, []).append(key)
            lines.append("  sources: " + "; ".join(f"from {s}: {', '.join(k)}" for s, k in by_source.items()))
        if self.defaults_taken:
            lines.append(f"defaults taken ({len(self.defaults_taken)}):")
            lines += [f"  DEFAULT {d.describe()}" for d in self.defaults_taken]
        else:
            lines.append("defaults taken: none")
        return lines

    def to_dict(self) -> dict:
        """JSON-able content of the study (stage params, caching keys): every resolved value, each data file's
        SHA-256, the defaults taken."""
        return {"version": VERSION, "path": None if self.path is None else str(self.path),
                "parameters": {"calibrated": {k: dict(v) for k, v in self.parameter_space.items()},
                               "fixed": dict(self.fixed)},
                "effects": dict(self.effects), "experiments": [e.to_dict() for e in self.experiments],
                "defaults_taken": [d.to_dict() for d in self.defaults_taken]}
