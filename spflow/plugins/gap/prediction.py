"""The prediction operator: a forward run seen through the data's own measurement chain, on the data's grid.

A prediction of an experiment is ``simulate`` (fine PV grid) followed by the *deterministic* part of that
experiment's measurement model (``spflow.synthetic.measure`` with every random error off: transducer sampling,
zero offset and drift, outlet dead volume, fraction-collector tubes; a tube without water gets its assays' zero-water
limit, so that a model producing only oil where the lab collected water is still compared, not undefined) and the
observations stage's resampling
(:func:`spflow.plugins.observations.on_simulator_grid`). Model and data are then compared like with like: a
dead volume or a transducer offset that the lab documented is not mistaken for a model gap.

:class:`Predictor` evaluates batches of model points (calibrated parameters in the unit box + effect strengths)
for a set of experiments, in parallel through a joblib ``Parallel`` when given, and memoises every run.
"""

from __future__ import annotations

import time
from collections.abc import Mapping, Sequence

import numpy as np
import xarray as xr

from spflow.plugins.forward.errors import SimulationError
from spflow.plugins.forward.simulate import simulate
from spflow.plugins.observations import on_simulator_grid
from spflow.synthetic import NoiseModel, measure

from .base_model import DEFAULT_PV_STEP, BaseModel
from .observed import Experiment

__all__ = ["measured_run", "Predictor"]

def _deterministic(noise: NoiseModel) -> NoiseModel:
    """The measurement model without its random errors (sampling, offset, drift and dead volume kept)."""
    return NoiseModel.exact(pressure_offset_pa=noise.pressure_offset_pa,
                            pressure_drift_pa_per_pv=noise.pressure_drift_pa_per_pv,
                            pressure_interval_pv=noise.pressure_interval_pv, tube_pv=noise.tube_pv,
                            dead_volume_ml=noise.dead_volume_ml)


def measured_run(exp: Experiment, params: Mapping[str, float], effects: Mapping[str, float], cells: int,
                 scheme: str = "tvd", pv_step: float = DEFAULT_PV_STEP) -> xr.Dataset | None:
    """The noise-free lab measurement (coreflood format) of a forward run of ``exp`` on ``cells`` cells with the
    transport ``scheme`` and output step ``pv_step`` (at most the data's grid step); ``None`` if the run fails."""
    try:
        sim = simulate(exp.schedule, {**exp.core, **params}, cells=cells, effects=dict(effects), scheme=scheme,
                       pv_step=min(pv_step, exp.pv_step))
    except SimulationError:
        return None
    return measure(sim, _deterministic(exp.measurement), 0, experiment=exp.name, source="spflow gap prediction",
                   empty_tubes="limit")


def _timed_run(*args) -> tuple[xr.Dataset | None, float]:
    """:func:`measured_run` and the CPU seconds it took (in the process that ran it)."""
    start = time.process_time()
    out = measured_run(*args)
    return out, time.process_time() - start


def _key(params: Mapping[str, float], effects: Mapping[str, float]) -> tuple:
    return (tuple(sorted((k, round(float(v), 12)) for k, v in params.items())),
            tuple(sorted((k, round(float(v), 12)) for k, v in effects.items())))


class Predictor:
    """Memoised, optionally parallel predictions of a base model (+ effect strengths) for given experiments."""

    def __init__(self, base: BaseModel, experiments: Sequence[Experiment], parallel=None):
        self.base = base
        self.experiments = {e.name: e for e in experiments}
        self.parallel = parallel
        self._runs: dict[tuple, xr.Dataset | None] = {}
        self._series: dict[tuple, np.ndarray] = {}
        self.runs = 0
        #: the phase of the diagnosis that new forward runs are charged to (``runs_by_phase``)
        self.phase = "other"
        self.runs_by_phase: dict[str, int] = {}
        #: CPU seconds of the forward runs (in the processes that ran them), in all and per phase
        self.run_cpu = 0.0
        self.run_cpu_by_phase: dict[str, float] = {}

    def model(self, u: np.ndarray, strengths: Mapping[str, float] | None = None):
        """(forward-model params, effect strengths) of unit-box point ``u`` with ``strengths`` over the base."""
        return self.base.forward_params(self.base.values(u)), {**self.base.effects, **(strengths or {})}

    def _resampled(self, key: tuple, exp: Experiment, variables: Sequence[str]) -> dict[str, np.ndarray] | None:
        lab = self._runs[key]
        if lab is None:
            return None
        todo = [v for v in variables if (key, v) not in self._series]
        if todo:
            for v, series in on_simulator_grid(lab, todo, exp.pv, exp.pv_step, exp.schedule.rate_steps_pv()).items():
                self._series[(key, v)] = series
        return {v: self._series[(key, v)] for v in variables}

    def predict(self, points: Sequence[tuple[np.ndarray, Mapping[str, float] | None]], experiments: Sequence[str],
                variables: Sequence[str] | None = None) -> list[dict[str, dict[str, np.ndarray]] | None]:
        """For each point ``(u, strengths)``: experiment -> variable -> series on its grid (``variables``, default
        every observed one), or ``None`` if any run failed."""
        models = [self.model(u, s) for u, s in points]
        todo = {}
        for params, effects in models:
            for name in experiments:
                key = (name,) + _key(params, effects)
                if key not in self._runs and key not in todo:
                    todo[key] = (self.experiments[name], params, effects)
        if todo:
            args = list(todo.values())
            numerics = (self.base.cells, self.base.scheme, self.base.pv_step)
            if self.parallel is not None and len(args) > 1:
                from joblib import delayed

                timed = self.parallel(delayed(_timed_run)(e, p, s, *numerics) for e, p, s in args)
            else:
                timed = [_timed_run(e, p, s, *numerics) for e, p, s in args]
            self._runs.update(zip(todo, (result for result, _ in timed)))
            cpu = sum(seconds for _, seconds in timed)
            self.runs += len(args)
            self.run_cpu += cpu
            self.runs_by_phase[self.phase] = self.runs_by_phase.get(self.phase, 0) + len(args)
            self.run_cpu_by_phase[self.phase] = self.run_cpu_by_phase.get(self.phase, 0.0) + cpu
        out = []
        for params, effects in models:
            series = {}
            for name in experiments:
                exp = self.experiments[name]
                series[name] = self._resampled((name,) + _key(params, effects), exp,
                                               list(exp.observed) if variables is None else
                                               [v for v in variables if v in exp.observed])
            out.append(None if any(v is None for v in series.values()) else series)
        return out
