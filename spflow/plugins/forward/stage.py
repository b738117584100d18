"""The ``forward`` stage: run the SP coreflood simulator over a design (sample x param) and a set of experiments.

Output dims (``sample``, ``experiment``, ``pv``): the response variables of :func:`simulate` on a common PV grid.
Experiments of different total PV share one grid (the union of their own grids, :func:`common_grid`) and are NaN
where a point is not theirs (past their end, or another experiment's off-step end point). An experiment is a
bundled name or a mapping ``{"name", "schedule", "params"}`` (:mod:`spflow.plugins.forward.experiments`) whose
``params`` override ``fixed`` for that experiment (its own core, rate, fluids); the sample's values override both.
A design row becomes forward-model parameters through the design's parameter map
(:class:`~spflow.plugins.design.parameter_map.ParameterMap`: a column may set several UTCHEM names, or hold log10 of
the value). Samples
run in parallel with the node's joblib budget; the simulator is deterministic, so serial and parallel runs are
bit-identical. Every sample's run arguments (parameters, effects, the injected-viscosity cap of
:mod:`~spflow.plugins.forward.injected_viscosity_cap`) are validated before any simulation starts.

Failure policy: a sample whose run of any experiment raises ``SimulationError`` (a time-step collapse, or a step or
wall-time budget exhausted, ``budgets``) does not abort the stage: its rows are NaN for every experiment and the
``failure`` variable (dim ``sample``) holds the reason (``"<experiment>: <message>"``; ``""`` for a sample that
ran). The stage warns with the count; stages consuming the responses drop failed samples and say how many.

Step control: the default ``capillary = "budgeted"`` is simulate's (the explicit scheme in every run inside half its
step budget; past it, the implicit capillary step and the implicit release of a phase near its residual where the
explicit limits would exceed the budget); the optional variables ``capillary_implicit_from_pv`` and
``oil_release_implicit_from_pv`` (dims ``sample``, ``experiment``) hold the PV of a run's first implicit capillary
step and first implicit release (NaN where it took none, and for failed samples), so a run that left the explicit
scheme is visible in the output.
"""

from __future__ import annotations

import warnings

import numpy as np
import xarray as xr

from spflow.core.params import Param
from spflow.core.schema import DatasetSchema, Variable
from spflow.core.stage import Stage, StageContext
from spflow.plugins.design.parameter_map import ParameterMap
from spflow.plugins.design.schemas import DESIGN
from spflow.plugins.forward.budgets import DEFAULT_MAX_WALL_S
from spflow.plugins.forward.errors import SimulationError
from spflow.plugins.forward.experiments import forward_experiments
from spflow.plugins.forward.numba_cache import source_digest
from spflow.plugins.forward.run_arguments import CAPILLARY, DEFAULT_CAPILLARY, validate_run
from spflow.plugins.forward.simulate import common_grid, simulate

#: Response variables of the simulator and their units.
RESPONSE_UNITS = {
    "dp": "Pa",
    "oil_cut": "1",
    "recovery": "1",
    "c_polymer_out": "ppm",
    "c_surfactant_out": "ppm",
    "salinity_out": "ppm",
}
#: Their long names.
RESPONSE_NAMES = {
    "dp": "pressure drop across the core",
    "oil_cut": "oil cut of the effluent",
    "recovery": "oil recovered, fraction of the oil in place",
    "c_polymer_out": "polymer concentration of the effluent",
    "c_surfactant_out": "surfactant concentration of the effluent",
    "salinity_out": "salinity of the effluent",
}

RESPONSES = DatasetSchema(
    dims=("sample", "experiment", "pv"),
    variables={
        name: Variable(("sample", "experiment", "pv"), units=unit, allow_nan=True, long_name=RESPONSE_NAMES[name])
        for name, unit in RESPONSE_UNITS.items()
    }
    | {"total_pv": Variable(("experiment",), units="1", long_name="pore volumes injected in the coreflood"),
       "failure": Variable(("sample",), kind="UO", required=False, long_name="why the sample's run failed",
                           doc="why a sample's run failed (its rows are NaN); empty for a sample that ran"),
       "capillary_implicit_from_pv": Variable(("sample", "experiment"), units="1", required=False, allow_nan=True,
                                              long_name="injected PV from which the run took the implicit "
                                                        "capillary step",
                                              doc="simulate's attr of that name: NaN where the run kept the "
                                                  "explicit capillary flux (or failed)"),
       "oil_release_implicit_from_pv": Variable(("sample", "experiment"), units="1", required=False, allow_nan=True,
                                                long_name="injected PV of the run's first implicit release",
                                                doc="simulate's attr of that name: NaN where the run took none (or "
                                                    "failed)")},
    doc="simulated coreflood responses",
)


def _run_sample(experiments, fixed, row, cells, effects, scheme, pv_step, max_steps, max_wall_s, capillary):
    """The runs of one sample for every experiment, or the failure reason (str) of the first failing run."""
    runs = []
    for exp in experiments:
        try:
            runs.append(simulate(exp.schedule, dict(fixed, **exp.params, **row), cells=cells, effects=effects,
                                 scheme=scheme, pv_step=pv_step, max_steps=max_steps or None, max_wall_s=max_wall_s,
                                 capillary=capillary))
        except SimulationError as err:
            return f"{exp.name}: {err}"
    return runs


class Forward(Stage):
    name = "forward"
    version = "5"
    description = "SP coreflood simulator over a design and a set of experiments"
    inputs = {"design": DESIGN}
    optional_inputs = frozenset({"design"})
    output = RESPONSES
    params = {
        "experiments": Param(list, ["BCF1", "BCF2", "BCF3"],
                             doc="bundled names (thesis Table 2.5) or {name, schedule, params} mappings"),
        "fixed": Param(dict, {}, doc="parameter overrides applied to every sample (UTCHEM names)"),
        "effects": Param(dict, {}, doc="effect name -> strength (0 = off); see `spflow list effects`"),
        "cells": Param(int, 100, bounds=(4, 5000), doc="grid cells"),
        "pv_step": Param(float, 0.1, bounds=(1e-4, 1.0), unit="PV", doc="output grid spacing"),
        "scheme": Param(str, "tvd", choices=["tvd", "upwind"], doc="transport scheme"),
        "max_steps": Param(int, 0, bounds=(0, None),
                           doc="step budget of each run; 0: simulate's default (50 x the expected steps)"),
        "max_wall_s": Param(float, DEFAULT_MAX_WALL_S, bounds=(1e-3, None), unit="s",
                            doc="wall-time budget of each run"),
        "capillary": Param(str, DEFAULT_CAPILLARY, choices=list(CAPILLARY),
                           doc="time discretisation of the capillary flux when capillary_pressure is on (simulate's "
                               "capillary: budgeted = the explicit scheme unless a run would need more than half its "
                               "step budget; docs/forward_model.md)"),
    }

    @classmethod
    def code_fingerprint(cls) -> str:
        """The stage's source plus every source file of the simulator, so that any physics edit reruns the node."""
        return f"{super().code_fingerprint()}-{source_digest()[:16]}"

    def __init__(self, **params):
        super().__init__(**params)
        forward_experiments(self.params["experiments"], self.params["fixed"])  # names, schedules, params: now

    def _rows(self, design: xr.Dataset | None) -> list[dict[str, float]]:
        if design is None:
            return [{}]
        mapping = ParameterMap.of(design)
        return [mapping.forward_params(values) for values in design["values"].values]

    def run(self, ctx: StageContext, design: xr.Dataset | None = None) -> xr.Dataset:
        fixed, effects = dict(self.params["fixed"]), dict(self.params["effects"])
        experiments = forward_experiments(self.params["experiments"], fixed)
        rows = self._rows(design)
        for row in rows:  # validate everything before any simulation (parameters, effects, viscosity cap)
            for exp in experiments:
                validate_run(exp.schedule, dict(fixed, **exp.params, **row), self.params["cells"], effects,
                             self.params["scheme"], self.params["pv_step"], None, 0.5)
        args = (self.params["cells"], effects, self.params["scheme"], self.params["pv_step"],
                self.params["max_steps"], self.params["max_wall_s"], self.params["capillary"])
        from joblib import delayed

        runs = ctx.parallel()(
            delayed(_run_sample)(experiments, fixed, row, *args) for row in ctx.progress(rows, what="samples")
        )
        total = np.array([e.schedule.total_pv for e in experiments])
        grid, positions = common_grid(total, self.params["pv_step"])
        data = {name: np.full((len(rows), len(experiments), grid.size), np.nan) for name in RESPONSE_UNITS}
        switch_pv = np.full((len(rows), len(experiments)), np.nan)
        release_pv = np.full((len(rows), len(experiments)), np.nan)
        failure = np.array([r if isinstance(r, str) else "" for r in runs], dtype=object)
        n_failed = int(np.count_nonzero(failure != ""))
        if n_failed:
            first = int(np.flatnonzero(failure != "")[0])
            warnings.warn(f"forward: {n_failed} of {len(rows)} samples failed (NaN rows, reason in the 'failure' "
                          f"variable); first: sample {first}: {failure[first]}", stacklevel=2)
        for i, sample_runs in enumerate(runs):
            if isinstance(sample_runs, str):
                continue
            for j, ds in enumerate(sample_runs):
                switch_pv[i, j] = ds.attrs["capillary_implicit_from_pv"]
                release_pv[i, j] = ds.attrs["oil_release_implicit_from_pv"]
                for name in RESPONSE_UNITS:
                    data[name][i, j, positions[j]] = ds[name].values
        out = xr.Dataset(
            {name: (("sample", "experiment", "pv"), values, {"units": RESPONSE_UNITS[name]})
             for name, values in data.items()}
            | {"total_pv": ("experiment", total, {"units": "1"}), "failure": ("sample", failure.astype(str)),
               "capillary_implicit_from_pv": (("sample", "experiment"), switch_pv, {"units": "1"}),
               "oil_release_implicit_from_pv": (("sample", "experiment"), release_pv, {"units": "1"})},
            coords={"sample": ("sample", np.arange(len(rows)), {"units": "1", "long_name": "sample number"}),
                    "experiment": ("experiment", [e.name for e in experiments], {"long_name": "coreflood"}),
                    "pv": ("pv", grid, {"units": "1", "long_name": "injected pore volumes"})},
            attrs={"cells": self.params["cells"], "scheme": self.params["scheme"]},
        )
        return RESPONSES.annotate(out)
