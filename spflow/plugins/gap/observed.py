"""Measured corefloods as a gap diagnosis sees them: values on the simulator grid plus the lab's measurement model.

Each coreflood (a bundled name, a netCDF or CSV file, or an in-memory Dataset in the format of
:mod:`spflow.io.format`) becomes an :class:`Experiment`: its schedule, its core data (``core_length_m`` ... attrs ->
``LENGTH`` ...), its measurement model (the ``noise_*`` attrs as a :class:`~spflow.synthetic.NoiseModel`; the
documented lab defaults when the file has none, which the report says), and every measured variable on the
simulator's output grid (:func:`spflow.plugins.observations.on_simulator_grid`: point values interpolated, tube
averages volume-averaged, NaN where not measured). :func:`observed_experiment` rebuilds the same
:class:`Experiment` from an ``observations`` stage output, which carries each coreflood's attrs; when that stage
moved the effluent series back by the outlet dead volume (its ``dead_volume_pv``), the series are those of the core
outlet and the Experiment's measurement model has no dead volume left.
"""

from __future__ import annotations

import json
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, fields, replace

import numpy as np
import xarray as xr

from spflow.core.errors import ParameterError
from spflow.io import load_coreflood
from spflow.io.csv_table import TUBE_ROWS_NOTE
from spflow.io.metadata import core_params
from spflow.plugins.forward.schedule import Schedule, as_schedule
from spflow.plugins.forward.run_arguments import common_grid, output_grid
from spflow.plugins.observations import on_simulator_grid
from spflow.synthetic import NoiseModel

__all__ = ["Experiment", "load_experiments", "measurement_note", "rate_step_note", "observed_experiment",
           "MEASURABLE"]

#: variables a diagnosis can use (the simulator's responses that a lab measures)
MEASURABLE = ("dp", "oil_cut", "recovery", "c_polymer_out", "c_surfactant_out", "salinity_out")


@dataclass(frozen=True)
class Experiment:
    """One coreflood on the simulator grid ``pv`` (step ``pv_step``) with its measurement model."""

    name: str
    schedule: Schedule
    core: dict[str, float]
    measurement: NoiseModel
    noise_from_data: bool
    pv: np.ndarray
    pv_step: float
    observed: dict[str, np.ndarray]
    pore_volume_ml: float | None
    ooip_ml: float | None
    source: str = "in-memory coreflood"
    #: what loading the file noticed about it (e.g. the CSV loader's ``tube_rows_note``), shown with the verdict
    data_notes: tuple[str, ...] = ()

    def slug_ends(self) -> np.ndarray:
        """Cumulative injected PV at the end of each slug."""
        return np.cumsum([s.pv for s in self.schedule.slugs])

    def slug_index(self, pv: np.ndarray) -> np.ndarray:
        """Index of the slug being injected at each PV (a point on a slug end belongs to the slug it ends)."""
        ends = self.slug_ends()
        return np.minimum(np.searchsorted(ends - 1e-9, pv), len(ends) - 1)


#: coreflood attrs that hold a loader's remark about the data (spflow.io.csv_table)
DATA_NOTE_ATTRS = (TUBE_ROWS_NOTE,)


def _noise(attrs: Mapping, name: str) -> tuple[NoiseModel, bool]:
    given = {f.name: float(attrs[f"noise_{f.name}"]) for f in fields(NoiseModel) if f"noise_{f.name}" in attrs}
    try:
        return NoiseModel(**given), len(given) == len(fields(NoiseModel))
    except ValueError as exc:
        raise ParameterError(f"coreflood {name!r}: measurement model attrs: {exc}") from None


def _from_attrs(name: str, schedule: Schedule, attrs: Mapping, pv: np.ndarray, pv_step: float,
                observed: dict[str, np.ndarray]) -> Experiment:
    """The :class:`Experiment` of coreflood attrs ``attrs`` (core data, ``noise_*``, volumes) and its series."""
    noise, from_data = _noise(attrs, name)
    core = core_params(attrs)
    return Experiment(name, schedule, core, noise, from_data, pv, pv_step, observed,
                      float(attrs["pore_volume_ml"]) if "pore_volume_ml" in attrs else None,
                      float(attrs["ooip_ml"]) if "ooip_ml" in attrs else None,
                      data_notes=tuple(str(attrs[k]) for k in DATA_NOTE_ATTRS if k in attrs))


def _experiment(ds: xr.Dataset, pv_step: float, schedules: Mapping[str, object]) -> Experiment:
    name = str(ds.attrs.get("experiment", "experiment"))
    if name in schedules:
        schedule = as_schedule(schedules[name])
    elif "schedule" in ds.attrs:
        schedule = as_schedule(json.loads(ds.attrs["schedule"]))
    else:
        raise ParameterError(f"coreflood {name!r} has no 'schedule' attr; give its schedule in the base model's "
                             f"[schedules] table ({name} = \"BCF1\" or a slug list)")
    if pv_step > schedule.total_pv:
        raise ParameterError(f"pv_step = {pv_step:g} PV exceeds the {schedule.total_pv:g} PV of {name!r}")
    grid = output_grid(schedule.total_pv, pv_step)
    present = [v for v in MEASURABLE if v in ds]
    if not present:
        raise ParameterError(f"coreflood {name!r} has none of the variables {list(MEASURABLE)}")
    observed = {v: s for v, s in on_simulator_grid(ds, present, grid, pv_step, schedule.rate_steps_pv()).items()
                if np.isfinite(s).any()}
    return _from_attrs(name, schedule, ds.attrs, grid, pv_step, observed)


def load_experiments(sources: Sequence, pv_step: float, schedules: Mapping[str, object] | None = None,
                     ) -> list[Experiment]:
    """Experiments from bundled names, file paths or in-memory coreflood Datasets; names must be distinct."""
    out = []
    for source in sources:
        if isinstance(source, xr.Dataset):
            ds = source
        else:
            try:
                ds = load_coreflood(source)
            except (ValueError, OSError) as exc:
                raise ParameterError(f"coreflood {source!r}: {exc}") from None
        exp = _experiment(ds, pv_step, schedules or {})
        # the file the data came from: the source given, else the file a loaded Dataset was read from
        origin = ds.encoding.get("source") if isinstance(source, xr.Dataset) else str(source)
        out.append(replace(exp, source=str(origin)) if origin else exp)
    names = [e.name for e in out]
    if len(set(names)) != len(names):
        raise ParameterError(f"experiments must have distinct names (attr 'experiment'), got {names}")
    return out


def measurement_note(experiments: Sequence[Experiment]) -> str | None:
    """The note naming the corefloods whose measurement model is not wholly in their data (``noise_*`` attrs, or
    CSV header keys) and the model the likelihood then uses for each (the documented lab defaults where the data
    are silent); ``None`` when every coreflood carries its own."""
    assumed = [e for e in experiments if not e.noise_from_data]
    if not assumed:
        return None
    models: dict[str, list[str]] = {}
    for e in assumed:
        text = ", ".join(f"{f.name} = {getattr(e.measurement, f.name):g}" for f in fields(NoiseModel))
        models.setdefault(text, []).append(e.name)
    used = "; ".join(f"{', '.join(names)}: {text}" for text, names in models.items())
    return (f"the measurement model of {', '.join(e.name for e in assumed)} is not wholly in the data (noise_* attrs "
            f"or CSV header keys; docs/data.md): where the data are silent the likelihood takes the documented lab "
            f"defaults (spflow.synthetic.NoiseModel). Used: {used}")


def rate_step_note(experiments: Sequence[Experiment]) -> str | None:
    """The note naming the rate steps across which no coreflood's Δp is interpolated (the data's or a prediction's,
    :func:`spflow.plugins.observations.on_simulator_grid`); ``None`` without rate steps."""
    steps = {e.name: e.schedule.rate_steps_pv() for e in experiments}
    listed = [f"{name} at {', '.join(f'{x:g}' for x in pv)} PV" for name, pv in steps.items() if pv.size]
    if not listed:
        return None
    return (f"injection-rate steps: {'; '.join(listed)}; Δp is not interpolated across them, and a point at a step "
            "is the ending slug's (docs/data.md, Rate steps in the data)")


def observed_experiment(observations: xr.Dataset, name: str) -> Experiment:
    """Experiment ``name`` of an ``observations`` stage output: its series on the experiment's own simulator grid
    and the schedule, core data and measurement model from the coreflood attrs the stage carries
    (``coreflood_attrs``). Equal to what :func:`load_experiments` makes of the same file at the same ``pv_step`` --
    of the file with its dead volume taken out (:func:`spflow.plugins.observations.at_core_outlet`, measurement model
    without dead volume) when the stage corrected for it (module docstring)."""
    names = [str(e) for e in observations["experiment"].values]
    if name not in names:
        raise ParameterError(f"experiment {name!r} is not in the observations; they have {names}")
    if "coreflood_attrs" not in observations.attrs:
        raise ParameterError("observations have no 'coreflood_attrs' attr (the measurement model of each coreflood); "
                             "produce them with the 'observations' stage")
    attrs = json.loads(observations.attrs["coreflood_attrs"])[name]
    step = float(observations.attrs["pv_step"])
    i = names.index(name)
    _, positions = common_grid(observations["total_pv"].values, step)
    own = output_grid(float(observations["total_pv"].values[i]), step)
    observed = {}
    for v in MEASURABLE:
        if v in observations:
            series = observations[v].values[i, positions[i]]
            if np.isfinite(series).any():
                observed[v] = series
    exp = _from_attrs(name, as_schedule(json.loads(attrs["schedule"])), attrs, own, step, observed)
    if "dead_volume_pv" in observations and float(observations["dead_volume_pv"].values[i]) > 0.0:
        exp = replace(exp, measurement=replace(exp.measurement, dead_volume_ml=0.0))  # already taken out
    return exp
