"""Tiny inputs for the built-in Dataset ports, so that conformance checks of a stage consuming them run in seconds: a
two-parameter space of the Table 3.1 parameters, a few Latin-hypercube points, 10-cell forward runs of BCF1 and the
bundled BCF1 observations. They come from the built-in stages themselves (``parameter_space``, ``lhs_design``,
``forward``, ``observations``), so they carry exactly the layout those stages produce."""

from __future__ import annotations

import xarray as xr

from spflow.core.plugins import get_registry
from spflow.core.stage import StageContext

__all__ = ["small_space", "small_design", "small_responses", "small_observations", "SMALL_CELLS"]

#: Grid cells of the small forward runs.
SMALL_CELLS = 10


def _run(stage: str, params: dict, **inputs: xr.Dataset) -> xr.Dataset:
    return get_registry().stage(stage)(**params).run(StageContext(node=f"small_inputs[{stage}]", verbose=False),
                                                      **inputs)


def small_space(names: tuple[str, ...] = ("AD41", "CRK"), relative: float = 0.3) -> xr.Dataset:
    """A ``parameter_space`` of ``names`` at ±``relative`` around the thesis defaults."""
    return _run("parameter_space", {"names": list(names), "relative": relative})


def small_design(space: xr.Dataset, samples: int = 6, seed: int = 1) -> xr.Dataset:
    """An ``lhs_design`` of ``samples`` points in ``space``."""
    return _run("lhs_design", {"samples": samples, "seed": seed}, space=space)


def small_responses(design: xr.Dataset, experiments: tuple[str, ...] = ("BCF1",)) -> xr.Dataset:
    """``forward`` runs of ``design`` on :data:`SMALL_CELLS` cells (tens of milliseconds each)."""
    return _run("forward", {"experiments": list(experiments), "cells": SMALL_CELLS}, design=design)


def small_observations(experiments: tuple[str, ...] = ("BCF1",)) -> xr.Dataset:
    """The bundled measurements of ``experiments`` on the simulator's 0.1 PV grid (``observations``)."""
    return _run("observations", {"experiments": list(experiments)})
