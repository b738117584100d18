"""What every screening stage shares (thesis Algorithm 1): parameters, checks, the forward runs and the output layout.

A subclass supplies the method: ``_runs(d)`` (model runs of a d-parameter design), ``_sample(...)`` (the design,
uniform on the box, or drawn from the marginals the space records: :mod:`.salib_glue`),
``_analyse(...)`` (per-QoI measures over (``qoi``, ``param``) plus the QoI ``variance``) and ``_score(...)``
(the selection score per parameter of one design). The base class

1. validates everything it can at construction (forward parameters, fixed values, effects, QoIs, selection rule)
   and everything that depends on the input space (groups, fixed/varied overlap) before any simulation;
2. builds one design per group (``mode = "per_group"``) or one over the space (``"joint"``), embeds them in full
   rows with the other parameters at the space's defaults, and runs them all in one ``forward`` stage call, so
   the simulations parallelise through ``ctx`` (:class:`spflow.plugins.forward.stage.Forward`);
3. turns the responses into QoIs (:mod:`.qois`), analyses each design, applies the selection rule
   (:mod:`.selection`) and returns the measures with the screened space (and its marginals, when it records any),
   group labels, scores and selection.

The marginals a space records (``distribution`` / ``distribution_parameters``, e.g. the ``priors`` stage's truncated
normals) must have the space's ranges as supports (as for the surrogates); the parameter a design holds fixed stays at
the space's ``default``. Which law each parameter was screened under is printed (``verbose``) and recorded in the
output (attr ``marginals``, and the two variables).
"""

from __future__ import annotations

import hashlib
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np
import xarray as xr

from spflow.core.errors import ParameterError
from spflow.core.params import Param
from spflow.core.stage import Stage, StageContext
from spflow.plugins.design.parameter_map import ParameterMap
from spflow.plugins.design.schemas import SPACE
from spflow.plugins.forward.effects import default_registry
from spflow.plugins.forward.failures import reject_failed
from spflow.plugins.forward.numba_cache import source_digest
from spflow.plugins.forward.experiments import forward_experiments
from spflow.plugins.forward.parameters import resolve_params
from spflow.plugins.forward.stage import Forward
from spflow.plugins.surrogates.input_marginals import marginal_variables
from spflow.plugins.surrogates.training_data import describe_marginals, space_marginals

from .groups import blocks_for, full_design, resolve_groups
from .qois import QOI_CHOICES, qoi_coords, qoi_matrix
from .selection import SELECTION_PARAMS, SelectionRule

__all__ = ["ScreeningStage", "SCREENING_PARAMS"]

_FORWARD_KEYS = ("experiments", "fixed", "effects", "cells", "pv_step")
_DEFAULT_QOIS = ["recovery_final", "dp_max"]

#: Parameters shared by the screening stages (the method adds its own).
SCREENING_PARAMS = {
    **{k: Forward.params[k] for k in _FORWARD_KEYS},
    "experiments": replace(Forward.params["experiments"], default=["BCF1"],
                           doc="bundled names or {name, schedule, params} mappings (the thesis screens on BCF1)"),
    "qois": Param(list, _DEFAULT_QOIS, choices=QOI_CHOICES,
                  doc="recovery_final, dp_max (per experiment) and/or response variables for per-time-step indices"),
    "select_on": Param(list, _DEFAULT_QOIS, choices=QOI_CHOICES, doc="QoIs (among qois) the selection score uses"),
    "groups": Param(dict, {}, doc="group (sub-model) -> parameter names partitioning the space; {}: one group"),
    "mode": Param(str, "per_group", choices=["per_group", "joint"],
                  doc="per_group: each group varied alone, others at defaults (thesis); joint: all together"),
    "seed": Param(int, 0, bounds=(0, 2**32 - 1), doc="seed of the designs and the bootstrap"),
    "conf_level": Param(float, 0.95, bounds=(0.5, 0.999), doc="confidence level of the bootstrap intervals"),
    "resamples": Param(int, 100, bounds=(10, 100_000), doc="bootstrap resamples of the intervals"),
    **SELECTION_PARAMS,
}


class ScreeningStage(Stage):
    """Base of the screening stages (module docstring); not registered itself."""

    inputs = {"space": SPACE}
    #: Short method name stored in ``attrs["method"]``.
    method = ""

    def __init__(self, **params):
        super().__init__(**params)
        where = f"stage {self.name!r} parameter"
        self._forward = Forward(**{k: self.params[k] for k in _FORWARD_KEYS})
        resolve_params(self.params["fixed"])
        default_registry().resolve(self.params["effects"])
        qois, select_on = list(self.params["qois"]), list(self.params["select_on"])
        if not qois or len(set(qois)) != len(qois):
            raise ParameterError(f"{where} 'qois' must be a non-empty list without repeats, got {qois!r}")
        if not select_on or any(q not in qois for q in select_on):
            raise ParameterError(f"{where} 'select_on' = {select_on!r} must be a non-empty subset of qois = {qois!r}")
        self.rule = SelectionRule.from_params(self.params)

    @classmethod
    def code_fingerprint(cls) -> str:
        """The screening package's sources (but the figure) plus the simulator's: an edit to either reruns the node."""
        h = hashlib.sha256(super().code_fingerprint().encode())
        for path in sorted(Path(__file__).parent.glob("*.py")):
            if path.name != "figure.py":
                h.update(path.read_bytes())
        return f"{h.hexdigest()[:16]}-{source_digest()[:16]}"

    # -- the method ------------------------------------------------------------------------------------------------
    def _runs(self, d: int) -> int:  # pragma: no cover - abstract
        raise NotImplementedError

    def _sample(self, names, lower, upper, rng, inputs) -> np.ndarray:  # pragma: no cover - abstract
        raise NotImplementedError

    def _analyse(self, names, x, y, lower, upper, rng) -> xr.Dataset:  # pragma: no cover - abstract
        raise NotImplementedError

    def _score(self, part: xr.Dataset, use: np.ndarray) -> xr.DataArray:  # pragma: no cover - abstract
        raise NotImplementedError

    def _attrs(self) -> dict:
        return {}

    # -- the shared procedure --------------------------------------------------------------------------------------
    def _checked_groups(self, names: list[str], mapping: ParameterMap) -> dict[str, list[str]]:
        groups = resolve_groups(self.name, names, self.params["groups"])
        overlap = sorted(set(self.params["fixed"]) & {n for column in mapping.names for n in column})
        if overlap:
            raise ParameterError(f"stage {self.name!r} parameter 'fixed' sets {overlap}, which the space varies; "
                                 "remove them from 'fixed' or from the space")
        return groups

    def run(self, ctx: StageContext, space: xr.Dataset) -> xr.Dataset:
        names = [str(n) for n in space["param"].values]
        mapping = ParameterMap.of(space)
        groups = self._checked_groups(names, mapping)
        lower, upper, default = (space[k].values.astype(float) for k in ("lower", "upper", "default"))
        recorded = space_marginals(space, names, lower, upper, f"stage {self.name!r}")
        printed, marginals = describe_marginals(names, lower, upper, recorded)
        if ctx.verbose:
            print(f"[{ctx.node}] screening under{printed}", file=sys.stderr, flush=True)
        blocks = blocks_for(names, groups, self.params["mode"], self._runs)
        streams = [s.spawn(2) for s in np.random.SeedSequence(self.params["seed"]).spawn(len(blocks))]
        samples = [self._sample(b.names, lower[b.columns], upper[b.columns], np.random.default_rng(s[0]),
                                None if recorded is None else [recorded[c] for c in b.columns])
                   for b, s in zip(blocks, streams)]
        design = mapping.design(full_design(default, blocks, samples))
        responses = self._forward.run(ctx, design=design)
        reject_failed(responses, f"stage {self.name!r}")
        y, index = qoi_matrix(responses, list(self.params["qois"]))
        use = np.isin(index.variable, list(self.params["select_on"]))
        parts = []
        for block, sample, stream in zip(blocks, samples, streams):
            part = self._analyse(block.names, sample, y[block.rows], lower[block.columns], upper[block.columns],
                                 np.random.default_rng(stream[1]))
            part["variance"] = part["variance"].broadcast_like(part["param"]).transpose("qoi", "param")
            part["score"] = self._score(part, use)
            part["score"].attrs = {"units": "1"}  # a number, whatever units the indices it is built from carry
            parts.append(part)
        out = xr.concat(parts, dim="param", join="outer", combine_attrs="override").reindex(param=names)
        if "param_j" in out.dims:
            out = out.reindex(param_j=names)
        out = out.assign_coords(qoi_coords(index))
        group_of = {n: g for g, members in groups.items() for n in members}
        out = out.assign_coords(group=("param", np.array([group_of[n] for n in names])))
        for k in ("lower", "upper", "default", "unit"):
            out[k] = space[k]
        if recorded is not None:
            out = out.assign(marginal_variables(recorded))
        out = mapping.attach(out)
        out["selected"] = ("param", self.rule.apply(out["score"].values, out["group"].values),
                           {"rule": self.rule.describe()})
        out.attrs = {
            "method": self.method,
            "mode": self.params["mode"],
            "experiments": ", ".join(e.name for e in forward_experiments(self.params["experiments"],
                                                                          self.params["fixed"])),
            "cells": self.params["cells"],
            "runs": int(design.sizes["sample"]),
            "seed": self.params["seed"],
            "conf_level": self.params["conf_level"],
            "select_on": ", ".join(self.params["select_on"]),
            "selection_rule": self.rule.describe(),
            "marginals": marginals,
            **self._attrs(),
        }
        return out
