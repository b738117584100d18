"""Training (or validation) data of a surrogate from the pipeline's Datasets: a parameter space, a design on it and
the simulator's responses at the design points.

Every surrogate stage (``pce``, ``adaptive_pce``, the Kriging ones, ``surrogate_validation``) reads its inputs through
these checks, so a design whose parameters differ from the space's, a responses Dataset of another length or a point
outside the box fails with one clear message before any fitting. Samples whose forward runs failed (the
``forward`` stage's ``failure`` variable) are dropped with a warning saying how many.

A space may record the marginal law of each parameter (``distribution`` / ``distribution_parameters``, as the
``priors`` stage writes for ``distribution="truncated_normal"``; :func:`.input_marginals.marginal_variables`). The
surrogate stages then fit under these marginals (:attr:`TrainingSet.inputs`). Each marginal's support must be the
space's range [lower, upper] -- uniform, truncated normal or beta -- since the designs are drawn inside that box.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import xarray as xr

from spflow.core.errors import ParameterError
from spflow.plugins.forward.failures import drop_failed

from .input_marginals import Marginal, Uniform, marginals_from_dataset
from .outputs import OutputIndex, stack_outputs

__all__ = ["TrainingSet", "design_points", "training_set", "space_marginals", "describe_marginals",
           "UNIFORM_ON_RANGES"]

#: The ``marginals`` attr of a stage that draws from a space recording no marginals.
UNIFORM_ON_RANGES = "uniform on the ranges (the space records no marginals)"


@dataclass(frozen=True)
class TrainingSet:
    """Points ``x`` (N, d) in physical units in the box ``lower``..``upper`` and outputs ``y`` (N, m); ``inputs``, the
    space's marginals (None: uniform on the box)."""

    names: list[str]
    lower: np.ndarray
    upper: np.ndarray
    x: np.ndarray
    y: np.ndarray
    outputs: OutputIndex
    inputs: list[Marginal] | None = None


def design_points(design: xr.Dataset, names: list[str], lower: np.ndarray, upper: np.ndarray) -> np.ndarray:
    """The design's points (N, d) with columns in the order of ``names``; all inside [lower, upper]."""
    have = [str(p) for p in design["param"].values]
    missing = [n for n in names if n not in have]
    if missing or len(have) != len(names):
        raise ParameterError(f"surrogate data: the design's parameters {have} must be exactly {names} "
                             f"(missing {missing})")
    x = design["values"].transpose("sample", "param").sel(param=names).values.astype(float)
    slack = 1e-9 * (upper - lower)
    outside = np.flatnonzero(((x < lower - slack) | (x > upper + slack)).any(axis=1))
    if outside.size:
        i = int(outside[0])
        raise ParameterError(f"surrogate data: design point {i} = {dict(zip(names, x[i]))} lies outside the box "
                             f"lower={dict(zip(names, lower))}, upper={dict(zip(names, upper))}")
    return np.clip(x, lower, upper)


def training_set(space: xr.Dataset, design: xr.Dataset, responses: xr.Dataset, variables: list[str],
                 experiments: list[str] | None) -> TrainingSet:
    """Points of ``design`` on ``space`` and the ``variables`` of ``responses`` (one row per design sample whose
    forward runs did not fail)."""
    names = [str(p) for p in space["param"].values]
    lower, upper = space["lower"].values.astype(float), space["upper"].values.astype(float)
    x = design_points(design, names, lower, upper)
    if responses.sizes.get("sample") != x.shape[0]:
        raise ParameterError(f"surrogate data: the responses have {responses.sizes.get('sample')} samples, the "
                             f"design {x.shape[0]} points")
    responses, kept = drop_failed(responses, "surrogate data")
    y, outputs = stack_outputs(responses, variables, experiments)
    return TrainingSet(names, lower, upper, x[kept], y, outputs, space_marginals(space, names, lower, upper))


def space_marginals(space: xr.Dataset, names: list[str], lower: np.ndarray, upper: np.ndarray,
                    where: str = "surrogate data") -> list[Marginal] | None:
    """The marginals a parameter ``space`` records (None when it records none), each with support [lower, upper];
    ``where`` (the stage reading the space) starts the error messages."""
    inputs = marginals_from_dataset(space, f"{where}: the parameter space")
    for name, marginal, lo, hi in zip(names, inputs or [], lower, upper):
        if marginal.support != (lo, hi):
            raise ParameterError(f"{where}: parameter {name!r} of the space has the distribution {marginal!r} "
                                 f"with support {marginal.support_text()}, not the space's range [{lo:g}, {hi:g}]; "
                                 f"a space's marginals must live on its range (uniform, truncated_normal or beta "
                                 f"with lower/upper = the range)")
    return inputs


def describe_marginals(names: list[str], lower: np.ndarray, upper: np.ndarray,
                       recorded: list[Marginal] | None) -> tuple[str, str]:
    """What a stage that draws from a space says of the laws it drew under (``recorded``: :func:`space_marginals`):
    (``printed``: ":" then one indented ``name ~ law`` line per parameter, after a note when the space records none
    and its ranges are taken as uniform; ``attr``: the output's ``marginals`` attr, those lines unindented, or
    :data:`UNIFORM_ON_RANGES`). A stage prints ``f"[{node}] <what it draws> under{printed}"`` (``verbose``)."""
    inputs = recorded or [Uniform(lo, hi) for lo, hi in zip(lower, upper)]
    laws = "\n".join(f"{n} ~ {m!r}" for n, m in zip(names, inputs))
    note = "" if recorded else " (the space records no marginals: uniform on its ranges)"
    return f"{note}:\n  " + laws.replace("\n", "\n  "), laws if recorded else UNIFORM_ON_RANGES
