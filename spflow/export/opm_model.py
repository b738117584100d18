"""The model an OPM Flow deck is written of, and where each of its values comes from.

:func:`export_opm` (``spflow export opm``) assembles a coreflood model from up to three layers and writes its deck
with :func:`~spflow.export.opm_deck.write_opm_deck`:

1. a study's experiment (:func:`spflow.load_study`): the schedule (with per-slug rates), the core (``LENGTH``,
   ``DIAMETER``, ``PORO``, ``PERM``, ``SWI``), the rate ``QINJ``, the experiment's fluids, the study's
   ``[parameters.fixed]`` and its base-model ``[effects]``;
2. one or more parameter sets: ``params`` (a mapping or a TOML/JSON file, flat ``{NAME = value}`` or with
   ``[parameters]``/``[effects]`` tables), ``calibration`` (the ``nsga2_calibration`` stage's Dataset or netCDF file:
   its ``confidence_best``, the design of the minimum χ² under the lab's measurement-error model, i.e. the
   noise-consistent best point) and ``posterior`` (an MCMC stage's Dataset or file, or the InferenceData file
   ``spflow run bayesian_calibration`` writes: draw ``draw`` of the chain-major flattened ``theta``, or ``"mean"``,
   the posterior mean over every chain and draw);
3. explicit ``schedule`` and ``effects``.

A later layer overrides an earlier one and the override is recorded with both sources; two parameter sets giving
the same parameter is a clash and raises :class:`~spflow.core.errors.ParameterError` naming both. A calibration or
posterior whose parameters are not the study's ``[parameters.calibrated]`` is noted (``NOTE`` lines). Everything is
checked before the deck is written. Every value taken is printed through ``log`` with its source and written into
the deck's header as comments (:attr:`ModelSources.lines`); parameters no layer gives take the forward model's
defaults, named in one line.
"""

from __future__ import annotations

import json
import tomllib
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import xarray as xr

from spflow.core.errors import ParameterError
from spflow.plugins.calibration.inference_data import read_posterior
from spflow.plugins.design.parameter_map import NAMES_VAR, ParameterMap
from spflow.plugins.forward import effects as E
from spflow.plugins.forward.parameters import PARAMETERS
from spflow.plugins.forward.schedule import as_schedule
from spflow.study import Study, load_study

from .opm_deck import OpmDeck, write_opm_deck

__all__ = ["ModelSources", "export_opm", "load_parameter_file", "calibration_parameters", "posterior_parameters",
           "resolve_model"]

_SPECS = {p.name: p for p in PARAMETERS}


def _unit(name: str) -> str:
    unit = _SPECS[name].unit
    return "" if unit in ("-", "") else f" {unit}"


@dataclass
class ModelSources:
    """The resolved inputs of a deck: ``schedule``, ``params`` and ``effects`` (what :func:`write_opm_deck` takes)
    and, per value, the source it was taken from (``param_source``, ``effect_source``, ``schedule_source``) and the
    overrides met on the way."""

    schedule: object = None
    schedule_source: str = ""
    params: dict[str, float] = field(default_factory=dict)
    param_source: dict[str, str] = field(default_factory=dict)
    effects: dict[str, float] = field(default_factory=dict)
    effect_source: dict[str, str] = field(default_factory=dict)
    overrides: list[str] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)

    def set_params(self, values: Mapping[str, float], source: str, *, clash_with: tuple[str, ...] = ()) -> None:
        """Take ``values`` from ``source``. A name already taken from one of the ``clash_with`` sources raises a
        ParameterError naming both; one taken from any other source is overridden and the override recorded."""
        for name, value in values.items():
            if name not in _SPECS:
                raise ParameterError(f"{source}: unknown forward-model parameter {name!r} (see `spflow list params`)")
            before = self.param_source.get(name)
            if before is not None and before in clash_with:
                raise ParameterError(f"parameter {name!r} is given twice: {self.params[name]:g} by {before} and "
                                     f"{float(value):g} by {source}; give each parameter in one parameter set only")
            if before is not None and float(value) != self.params[name]:
                self.overrides.append(f"{name} = {float(value):g}{_unit(name)} from {source} overrides "
                                      f"{self.params[name]:g} from {before}")
            self.params[name] = float(value)
            self.param_source[name] = source

    def set_effects(self, values: Mapping[str, float], source: str) -> None:
        """Take effect strengths from ``source`` (a later source overrides, recorded)."""
        for name, value in values.items():
            before = self.effect_source.get(name)
            if before is not None and float(value) != self.effects[name]:
                self.overrides.append(f"effect {name} = {float(value):g} from {source} overrides "
                                      f"{self.effects[name]:g} from {before}")
            self.effects[name] = float(value)
            self.effect_source[name] = source

    def lines(self) -> list[str]:
        """Text lines: the schedule, every parameter and effect with its source, the overrides, the defaults."""
        out = [f"schedule {self.schedule.name!r} from {self.schedule_source}"]
        out += [f"parameter {n} = {v:.10g}{_unit(n)} from {self.param_source[n]}" for n, v in self.params.items()]
        defaults = [n for n in _SPECS if n not in self.params]
        out.append(f"parameters at the forward model's defaults ({len(defaults)}, `spflow list params`): "
                   + ", ".join(defaults))
        registry = E.default_registry().resolve(None)
        out += [f"effect {n} = {v:g} from {self.effect_source[n]}" for n, v in self.effects.items()]
        rest = [n for n in registry if n not in self.effects]
        if rest:
            out.append("effects at the registry's default strengths: "
                       + ", ".join(f"{n} = {registry[n]:g}" for n in rest))
        out += [f"OVERRIDE {o}" for o in self.overrides]
        out += [f"NOTE {n}" for n in self.notes]
        return out


def _read_text_file(path, what: str) -> dict:
    file = Path(path)
    if not file.is_file():
        raise ParameterError(f"{what} {str(path)!r}: no such file")
    try:
        if file.suffix.lower() == ".json":
            return json.loads(file.read_text())
        with file.open("rb") as fh:
            return tomllib.load(fh)
    except (tomllib.TOMLDecodeError, json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise ParameterError(f"{what} {str(path)!r}: not valid {file.suffix.lstrip('.').upper() or 'TOML'}: "
                             f"{exc}") from None


def load_parameter_file(path, what: str = "--params") -> tuple[dict, dict]:
    """``(parameters, effects)`` of a TOML/JSON file: a flat ``{NAME = value}`` table or ``[parameters]`` and
    ``[effects]`` tables."""
    data = _read_text_file(path, what)
    if "parameters" in data or "effects" in data:
        unknown = sorted(set(data) - {"parameters", "effects"})
        if unknown:
            raise ParameterError(f"{what} {str(path)!r}: unknown table(s) {unknown}; allowed "
                                 "['parameters', 'effects'] or a flat NAME = value table")
        return dict(data.get("parameters", {})), dict(data.get("effects", {}))
    return dict(data), {}


def _dataset(source, what: str, needs: tuple[str, ...], stages: str, grouped=None) -> tuple[xr.Dataset, str]:
    """The Dataset ``source`` (or the netCDF file it names) with the variables ``needs``; ``grouped(path)`` reads a
    file whose root group lacks them (a file of netCDF groups, e.g. ArviZ InferenceData)."""
    if isinstance(source, xr.Dataset):
        ds, where = source, f"{what} (Dataset)"
    else:
        where = f"{what} {str(source)!r}"
        if not Path(source).is_file():
            raise ParameterError(f"{where}: no such file")
        try:
            with xr.open_dataset(source) as opened:
                ds = opened.load()
        except (OSError, ValueError) as exc:
            raise ParameterError(f"{where}: not a readable netCDF file ({exc})") from None
    missing = [v for v in needs if v not in ds.variables]
    if missing and grouped is not None and not isinstance(source, xr.Dataset) and not ds.variables:
        ds = grouped(source)
        missing = [v for v in needs if v not in ds.variables]
    if missing:
        raise ParameterError(f"{where}: no variable(s) {missing}; expected the output of {stages} with "
                             f"{list(needs)}")
    return ds, where


def _named(ds: xr.Dataset, values, where: str, study) -> dict[str, float]:
    """Forward-model parameters of a calibration's or posterior's point ``values`` (one per ``param`` label) through
    the parameter map the Dataset carries (:mod:`spflow.plugins.design.parameter_map`); a file written before the
    map was recorded: a label is a forward-model name, or a study's calibrated label with several ``names`` (each
    takes the value)."""
    labels = [str(label) for label in ds["param"].values]
    for label, value in zip(labels, values):
        if not np.isfinite(value):
            raise ParameterError(f"{where}: parameter {label!r} is {value!r}, not a finite number")
    if NAMES_VAR in ds:
        return ParameterMap.of(ds).forward_params(values)
    space = {} if study is None else study.parameter_space
    unknown = [label for label in labels if label not in _SPECS and label not in space]
    if unknown:
        raise ParameterError(f"{where}: parameter {unknown[0]!r} is neither a forward-model parameter nor a "
                             f"calibrated label of the study (labels: {sorted(space)})")
    names = tuple(tuple(space[label]["names"]) if label not in _SPECS else (label,) for label in labels)
    return ParameterMap(tuple(labels), names, (False,) * len(labels)).forward_params(values)


def calibration_parameters(calibration, study=None) -> tuple[dict[str, float], str]:
    """The noise-consistent best point of an ``nsga2_calibration`` result (Dataset or netCDF file): the
    ``confidence_best`` design (minimum χ² under the lab's measurement-error model). Returns the parameters and a
    description of the source."""
    ds, where = _dataset(calibration, "--calibration", ("confidence_best", "param"),
                         "the nsga2_calibration stage (version 3 or later; rerun the node for an older file)")
    chi2 = ds.attrs.get("confidence_chi2_min")
    detail = "confidence_best, the minimum-chi2 design" + ("" if chi2 is None else f" (chi2 = {float(chi2):.6g})")
    return _named(ds, ds["confidence_best"].values.astype(float), where, study), f"{where} {detail}"


def posterior_parameters(posterior, draw, study=None) -> tuple[dict[str, float], str]:
    """A posterior sample of an MCMC stage's result (Dataset or netCDF file): ``draw`` = an index into the
    chain-major flattened draws (chain ``draw // n_draw``, draw ``draw % n_draw``), or ``"mean"``, the posterior
    mean over every chain and draw. Returns the parameters and a description of the source."""
    ds, where = _dataset(posterior, "--posterior", ("theta", "param"), "an MCMC stage (emcee_sampler, mh_sampler)",
                         grouped=read_posterior)
    theta = ds["theta"].transpose("chain", "draw", "param").values.astype(float)
    n_chain, n_draw = theta.shape[:2]
    flat = theta.reshape(-1, theta.shape[-1])
    if isinstance(draw, str) and draw.strip().lower() == "mean":
        values, detail = flat.mean(axis=0), f"posterior mean of {flat.shape[0]} draws ({n_chain} chains)"
    else:
        try:
            k = int(draw)
        except (TypeError, ValueError):
            k = -1
        if isinstance(draw, bool) or k < 0 or k >= flat.shape[0] or str(k) != str(draw).strip():
            raise ParameterError(f"{where}: draw = {draw!r}; allowed 'mean' or an integer in [0, {flat.shape[0] - 1}]"
                                 f" ({n_chain} chains x {n_draw} draws, chain-major)")
        values, detail = flat[k], f"draw {k} (chain {k // n_draw}, draw {k % n_draw})"
    return _named(ds, values, where, study), f"{where} {detail}"


def _space_mismatch(values: Mapping[str, float], study, source: str) -> list[str]:
    """Notes when a calibration's parameters are not the study's ``[parameters.calibrated]`` (a calibration of
    another study, e.g. a built-in pipeline's run on the bundled corefloods)."""
    calibrated = [n for spec in study.parameter_space.values() for n in spec["names"]]
    extra, missing = [n for n in values if n not in calibrated], [n for n in calibrated if n not in values]
    notes = []
    if extra:
        notes.append(f"{source} sets {extra}, which the study does not calibrate")
    if missing:
        notes.append(f"the study calibrates {missing}, which {source} does not give: they keep the study's or "
                     "the model's values above")
    return notes


def resolve_model(*, study=None, experiment: str | None = None, schedule=None, params=None, effects=None,
                  calibration=None, posterior=None, draw=None) -> ModelSources:
    """The layers of the module docstring resolved into a :class:`ModelSources`; ``study`` is a Study or a study
    file; ``params`` a mapping or a TOML/JSON file. Every conflict is raised before anything is written."""
    if (study is None) != (experiment is None):
        raise ParameterError("a study needs an experiment and an experiment needs a study: give both --study FILE "
                             "and --experiment NAME, or neither")
    if calibration is not None and posterior is not None:
        raise ParameterError("give one parameter source of a calibration run: --calibration FILE or --posterior FILE, "
                             "not both")
    if posterior is None and draw is not None:
        raise ParameterError("--draw selects a posterior sample; give it with --posterior FILE")
    if posterior is not None and draw is None:
        raise ParameterError("--posterior needs --draw K (an index) or --draw mean")
    m = ModelSources()
    if study is not None:
        study = study if isinstance(study, Study) else load_study(study)
        where = str(study.path) if study.path is not None else "(in memory)"
        exp = study.experiment(experiment)
        m.schedule, m.schedule_source = exp.schedule, f"study {where} experiment {experiment!r}"
        m.set_params(study.fixed, f"study {where} [parameters.fixed]")
        m.set_params(exp.model_params(), f"study {where} experiment {experiment!r}")
        defaulted = {d.field.removeprefix("effects.") for d in study.defaults_taken
                     if d.experiment is None and d.field.startswith("effects.")}
        m.set_effects({k: v for k, v in study.effects.items() if k not in defaulted}, f"study {where} [effects]")
        m.set_effects({k: v for k, v in study.effects.items() if k in defaulted},
                      f"the registry's default (not listed in [effects] of study {where})")
    if schedule is not None:
        source = "--schedule"
        if isinstance(schedule, (str, Path)) and Path(schedule).suffix.lower() in (".toml", ".json"):
            source = f"--schedule {str(schedule)!r}"
            schedule = _read_text_file(schedule, "--schedule")
        elif isinstance(schedule, str):
            source = f"--schedule {schedule!r}"
        sched = as_schedule(schedule)
        if m.schedule is not None:
            m.overrides.append(f"schedule {sched.name!r} from {source} overrides {m.schedule.name!r} from "
                               f"{m.schedule_source}")
        m.schedule, m.schedule_source = sched, source
    if m.schedule is None:
        raise ParameterError("no schedule: give --schedule NAME|FILE or --study FILE --experiment NAME")
    sets: list[str] = []
    if params is not None:
        if isinstance(params, Mapping):
            values, file_effects, source = dict(params), {}, "params"
        else:
            values, file_effects = load_parameter_file(params)
            source = f"--params {str(params)!r}"
        m.set_params(values, source)
        m.set_effects(file_effects, source)
        sets.append(source)
    for given, reader in ((calibration, lambda: calibration_parameters(calibration, study)),
                          (posterior, lambda: posterior_parameters(posterior, draw, study))):
        if given is not None:
            values, source = reader()
            m.set_params(values, source, clash_with=tuple(sets))
            if study is not None:
                m.notes += _space_mismatch(values, study, source)
    if effects:
        m.set_effects(effects, "--effect")
    return m


def export_opm(out_dir, *, study=None, experiment: str | None = None, schedule=None, params=None, effects=None,
               calibration=None, posterior=None, draw=None, cells: int = 100, log=print, **deck_options) -> OpmDeck:
    """Write ``out_dir/CORE.DATA``, the OPM Flow deck of a study's experiment and/or an explicit schedule under a
    parameter set (module docstring); every value taken is printed through ``log`` and written into the deck
    header. ``deck_options`` go to :func:`~spflow.export.opm_deck.write_opm_deck`."""
    model = resolve_model(study=study, experiment=experiment, schedule=schedule, params=params, effects=effects,
                          calibration=calibration, posterior=posterior, draw=draw)
    lines = model.lines()
    for line in lines:
        log(line)
    return write_opm_deck(Path(out_dir) / "CORE.DATA", model.schedule, model.params, model.effects, cells, log=log,
                          provenance=lines, **deck_options)
