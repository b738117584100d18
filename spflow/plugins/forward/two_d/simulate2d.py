"""``simulate2d()``: the SP coreflood on a heterogeneous 2-D (x-y) core (thesis sec. 1.8), reached through
``spflow.simulate(schedule, params, cells=(nx, ny), permeability=...)``.

Same schedule, parameters, effects and output series as the 1-D model (``simulate.simulate``); the core is a
``LENGTH`` x ``DIAMETER`` slab (aspect ratio ``DIAMETER / LENGTH``) with the mean Darcy velocity ``QINJ / A`` of the
1-D core, so the pore-volume time scale is the same. Per-slug injection rates (``Slug.rate_ml_min``) are 1-D only:
a 2-D run rejects a slug whose rate differs from QINJ. ``PERM`` is the reference permeability (the 1-D value; a
uniform field when ``permeability`` is None).
"""

from __future__ import annotations

import time

import numpy as np
import xarray as xr
from threadpoolctl import threadpool_limits

from spflow.core.errors import ParameterError

from .. import effects as E
from .. import kernel_inputs as K
from .. import state_layout as L
from ..errors import SimulationError
from ..kernel_inputs import build_kernel_params
from ..outputs import PROFILE_VARIABLES, build_dataset
from ..checks import check_number
from ..run_arguments import SCHEMES, output_grid, validate_run
from .grid2d import Grid2D
from .kernel2d import run_kernel2d
from .pressure2d import METHODS

__all__ = ["simulate2d", "MAX_CELLS_2D"]

MAX_CELLS_2D = 200_000
_MAX_NX, _MAX_NY = 20000, 4000


def _check_cells_2d(cells):
    """``(nx, ny)`` with ``3 <= nx``, ``1 <= ny`` and ``nx * ny <= MAX_CELLS_2D``."""
    if not isinstance(cells, (tuple, list)) or len(cells) != 2:
        raise ParameterError(f"cells must be a pair (nx, ny) for a 2-D run (nx in [3, {_MAX_NX}], ny in "
                             f"[1, {_MAX_NY}], nx * ny <= {MAX_CELLS_2D}), got {cells!r}")
    for name, v, lo, hi in (("cells[0] (nx)", cells[0], 3, _MAX_NX), ("cells[1] (ny)", cells[1], 1, _MAX_NY)):
        if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or not lo <= v <= hi:
            raise ParameterError(f"{name} must be an integer in [{lo}, {hi}], got {v!r}")
    nx, ny = int(cells[0]), int(cells[1])
    if nx * ny > MAX_CELLS_2D:
        raise ParameterError(f"cells = ({nx}, {ny}) has {nx * ny} cells; allowed nx * ny <= {MAX_CELLS_2D}")
    return nx, ny


def _check_permeability(permeability, nx, ny):
    """``permeability`` (mD) as a float array ``[ny, nx]``: positive and finite; a DataArray must have dims
    (``y``, ``x``)."""
    if isinstance(permeability, xr.DataArray):
        if permeability.dims != ("y", "x"):
            raise ParameterError(f"permeability must have dims ('y', 'x'), got {permeability.dims}")
        unit = permeability.attrs.get("units", "mD")
        if unit != "mD":
            raise ParameterError(f"permeability must be in mD, got units {unit!r}")
        permeability = permeability.values
    try:
        k = np.asarray(permeability, dtype=np.float64)
    except (TypeError, ValueError):
        raise ParameterError("permeability must be an array of numbers (mD) of shape (ny, nx)") from None
    if k.shape != (ny, nx):
        raise ParameterError(f"permeability must have shape (ny, nx) = ({ny}, {nx}) for cells = ({nx}, {ny}), "
                             f"got {k.shape}")
    if not np.all(np.isfinite(k)) or not np.all(k > 0.0):
        raise ParameterError("permeability must be finite and > 0 mD in every cell; allowed (0, 1e5] mD")
    if k.max() > 1.0e5:
        raise ParameterError(f"permeability max {k.max():g} mD is out of range; allowed (0, 1e5] mD")
    return k


def simulate2d(schedule, params=None, *, cells=(100, 20), permeability=None, effects=None, scheme="tvd",
               pv_step=0.01, profiles_at=None, cfl=0.5, alpha_t_ratio=None, pressure_every=None,
               pressure_solver="pcg"):
    """Run one SP coreflood on a 2-D core and return an ``xarray.Dataset``.

    Arguments as ``simulate.simulate`` plus: ``cells = (nx, ny)``; ``permeability`` (mD, shape ``(ny, nx)`` or a
    DataArray on (``y``, ``x``) such as ``permeability_field(nx, ny)``; None: uniform ``PERM``); ``alpha_t_ratio``
    the transverse/longitudinal dispersivity ratio (default 0.1); ``pressure_every`` (default 1: IMPES) solves the
    pressure every that many steps and at every slug end, output and profile time (``kernel2d``);
    ``pressure_solver`` ``"pcg"`` (default: CG preconditioned with a reused LU, flux-corrected to divergence-free)
    or ``"direct"`` (LU every solve), see ``pressure2d``. Capillary pressure is not available in 2-D.

    Returns the 1-D series on ``pv`` (``dp`` injector-well minus producer pressure, ``oil_cut``, ``recovery``,
    effluent concentrations: rate-weighted over the producer line); with ``profiles_at`` the maps of the 1-D
    profiles on (``profile_pv``, ``y``, ``x``); ``permeability`` on (``y``, ``x``); attrs as in 1-D (per-component
    relative mass-balance error, ``n_steps``, ``wall_time_s``) plus ``nx``, ``ny``, ``aspect``, ``alpha_t_ratio``,
    ``pressure_every``, ``pressure_solver``, ``n_pressure_solves``, ``n_pressure_factorizations``,
    ``n_pressure_iterations`` (PCG), ``pressure_time_s`` (wall time in the pressure solves).
    """
    sched, resolved, strengths, registry, (nx, ny), pv_step, prof, cfl = validate_run(
        schedule, params, cells, effects, scheme, pv_step, profiles_at, cfl, check_cells=_check_cells_2d
    )
    for i, slug in enumerate(sched.slugs):
        if slug.rate_ml_min is not None and slug.rate_ml_min != resolved["QINJ"]:
            raise ParameterError(f"slug {i} ({slug.name!r}): field 'rate_ml_min' = {slug.rate_ml_min!r} ml/min is not "
                                 f"available in 2-D runs (one rate, QINJ = {resolved['QINJ']!r} ml/min); per-slug "
                                 "rates run in 1-D")
    alpha_t_ratio = 0.1 if alpha_t_ratio is None else check_number("alpha_t_ratio", alpha_t_ratio, 0.0, 1.0)
    if pressure_every is None:
        pressure_every = 1
    elif isinstance(pressure_every, bool) or not isinstance(pressure_every, (int, np.integer)) or not (
            1 <= pressure_every <= 1000):
        raise ParameterError(f"pressure_every must be an integer in [1, 1000], got {pressure_every!r}")
    if pressure_solver not in METHODS:
        raise ParameterError(f"pressure_solver must be one of {METHODS}, got {pressure_solver!r}")
    perm = np.full((ny, nx), resolved["PERM"]) if permeability is None else _check_permeability(permeability, nx, ny)
    prm = build_kernel_params(resolved, strengths)
    if prm[K.PC0] > 0.0:
        raise ParameterError("capillary_pressure must be 0 (off) in 2-D runs: the 2-D model has no capillary "
                             f"fluxes; got strength {strengths['capillary_pressure']!r}")
    arrays = sched.kernel_arrays()
    inj = np.ascontiguousarray(np.vstack([arrays["c3"], arrays["c4"], arrays["c5"], arrays["c6"]]))
    out_pv = output_grid(sched.total_pv, pv_step)
    end_pv = arrays["end_pv"].copy()
    end_pv[-1] = out_pv[-1]
    aspect = resolved["DIAMETER"] / resolved["LENGTH"]
    grid = Grid2D(nx, ny, aspect, perm / resolved["PERM"])

    start = time.perf_counter()
    with threadpool_limits(1, "blas"):  # the PCG's vector operations are too small for threaded BLAS (pressure2d)
        status, info, n_steps, solver, series, maps, totals, _ = run_kernel2d(
            prm, end_pv, inj, out_pv, prof, grid, SCHEMES[scheme], cfl, alpha_t_ratio, int(pressure_every),
            pressure_solver
        )
    wall = time.perf_counter() - start
    if status != L.OK:
        err = SimulationError(status, info, grid.n)
        err.add_note(f"2-D grid {nx} x {ny}: flattened cell {err.cell} is (ix, iy) = "
                     f"({err.cell % nx}, {err.cell // nx})")
        raise err

    attrs = {"schedule": sched.name, "cells": nx * ny, "nx": nx, "ny": ny, "aspect": aspect, "scheme": scheme,
             "cfl": cfl, "pv_step": pv_step, "alpha_t_ratio": alpha_t_ratio, "pressure_every": int(pressure_every),
             "n_steps": int(n_steps), "pressure_solver": pressure_solver, "n_pressure_solves": solver.n_solves,
             "n_pressure_factorizations": solver.n_factorizations, "n_pressure_iterations": solver.n_iterations,
             "pressure_time_s": solver.wall_s, "wall_time_s": wall}
    attrs.update({f"param_{k}": v for k, v in resolved.items()})
    attrs.update({f"effect_{k}": v for k, v in strengths.items()})
    ds = build_dataset(series, maps, totals, out_pv, np.zeros(0), grid.n, attrs)
    ds = ds.assign_coords(
        x=("x", (np.arange(nx) + 0.5) / nx, {"units": "1", "long_name": "cell-centre x / L"}),
        y=("y", (np.arange(ny) + 0.5) * grid.dy, {"units": "1", "long_name": "cell-centre y / L"}),
    )
    ds["permeability"] = (("y", "x"), perm, {"units": "mD", "long_name": "absolute permeability"})
    if prof.size:
        ds = ds.assign_coords(profile_pv=("profile_pv", prof, {"units": "PV", "long_name": "profile time"}))
        for name, row, unit, long_name, scale in PROFILE_VARIABLES:
            ds[name] = (("profile_pv", "y", "x"), maps[row].reshape(prof.size, ny, nx) * scale,
                        {"units": unit, "long_name": long_name})
    for name, s in strengths.items():
        effect = registry[name]
        if name not in E.BUILTIN_NAMES and effect.transform_output is not None:
            ds = effect.transform_output(ds, s)
    return ds
