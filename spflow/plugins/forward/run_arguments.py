"""The arguments of a forward run, checked before any work, and the output grid they define (shared by the 1-D
``simulate()`` and the 2-D ``simulate2d()``)."""

from __future__ import annotations

import math

import numpy as np

from spflow.core.errors import ParameterError

from . import effects as E
from . import state_layout as L
from .checks import check_number
from .parameters import resolve_params
from .injected_viscosity_cap import check_injected_viscosity
from .schedule import as_schedule

__all__ = ["SCHEMES", "CAPILLARY", "DEFAULT_CAPILLARY", "MAX_CELLS", "output_grid", "common_grid", "validate_run"]

#: transport schemes: name -> second order (TVD) or not
SCHEMES = {"tvd": True, "upwind": False}
#: capillary time discretisations: name -> the kernel's capillary mode
CAPILLARY = {"budgeted": L.CAP_BUDGETED, "explicit": L.CAP_EXPLICIT, "implicit": L.CAP_IMPLICIT,
             "adaptive": L.CAP_ADAPTIVE}
#: the default capillary time discretisation (simulate's and the forward stage's)
DEFAULT_CAPILLARY = "budgeted"
#: the largest 1-D grid
MAX_CELLS = 20000


def output_grid(total_pv: float, pv_step: float) -> np.ndarray:
    """``0, pv_step, 2 pv_step, ...`` up to and including ``total_pv`` (appended if not on the step grid)."""
    n = int(math.floor(total_pv / pv_step + 1.0e-9))
    grid = np.arange(n + 1, dtype=np.float64) * pv_step
    if total_pv - grid[-1] > 1.0e-9 * max(1.0, total_pv):
        grid = np.append(grid, total_pv)
    else:
        grid[-1] = total_pv
    return grid


def common_grid(totals, pv_step: float) -> tuple[np.ndarray, list[np.ndarray]]:
    """The union of several experiments' output grids and, per experiment, the positions of its own grid in it.

    Experiments of different length share the step points; each one's off-step end point (e.g. 4.23 PV) is a
    point of the union that the others leave NaN. Points are matched rounded to 1e-9 PV, so ``41 * 0.1`` and an
    end point of exactly 4.1 are one point; the union holds the rounded values.
    """
    grids = [np.round(output_grid(float(t), pv_step), 9) for t in totals]
    union = np.unique(np.concatenate(grids))
    return union, [np.searchsorted(union, g) for g in grids]


def _check_cells(cells):
    if isinstance(cells, bool) or not isinstance(cells, (int, np.integer)) or not 3 <= cells <= MAX_CELLS:
        raise ParameterError(f"cells must be an integer in [3, {MAX_CELLS}], got {cells!r}")
    return int(cells)


def validate_run(schedule, params, cells, effects, scheme, pv_step, profiles_at, cfl, check_cells=_check_cells):
    """Every argument of a run checked before any work (``ParameterError`` naming the argument and its allowed
    range; the viscosity of the run's injected fluids against its physical cap, ``injected_viscosity_cap``):
    returns ``(schedule, resolved parameters, effect strengths, effect registry, cells, pv_step, profile times,
    cfl)``. ``check_cells`` validates ``cells`` (1-D: an integer; the 2-D model passes its own)."""
    sched = as_schedule(schedule)
    total = sched.total_pv
    cells = check_cells(cells)
    if scheme not in SCHEMES:
        raise ParameterError(f"scheme must be one of {sorted(SCHEMES)}, got {scheme!r}")
    pv_step = check_number("pv_step", pv_step, 0.0, total, lower_open=True)
    if total / pv_step > 1.0e6:
        raise ParameterError(f"pv_step = {pv_step!r} gives more than 1e6 output points; allowed [{total / 1e6:g}, "
                             f"{total:g}] PV for this schedule")
    cfl = check_number("cfl", cfl, 0.0, 0.5 if scheme == "tvd" else 1.0, lower_open=True)
    if profiles_at is None:
        prof = np.zeros(0)
    else:
        values = np.atleast_1d(np.asarray(profiles_at, dtype=object))
        # tolerate the round-off of the slug sum (0.6 + 0.5 + 0.7 = 1.7999999999999998)
        limit = total * (1.0 + 1e-12)
        prof = np.array([check_number(f"profiles_at[{i}]", v, 0.0, limit)
                         for i, v in enumerate(values)], dtype=np.float64)
        prof = np.unique(np.minimum(prof, total))
    registry = E.default_registry()
    strengths = registry.resolve(effects)
    resolved = resolve_params(params)
    for name, s in strengths.items():
        effect = registry[name]
        if name not in E.BUILTIN_NAMES and effect.transform_params is not None:
            resolved = resolve_params(effect.transform_params(dict(resolved), s))
    check_injected_viscosity(resolved, strengths, sched)
    return sched, resolved, strengths, registry, cells, pv_step, prof, cfl
