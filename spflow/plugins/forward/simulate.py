"""``simulate()``: the public entry point of the SP coreflood forward model (re-exported as ``spflow.simulate``).

Python validates every input before any work, converts units, calls the compiled kernel once and builds the
Dataset; nothing loops over cells or steps here.
"""

from __future__ import annotations

import time

import numpy as np

from spflow.core.errors import ParameterError

from . import effects as E
from . import state_layout as L
from .errors import SimulationError
from .budgets import resolve_budgets, wall_clock_flag
from . import kernel_inputs as K
from .kernel_inputs import build_kernel_params, slug_flow
from .run_arguments import CAPILLARY, DEFAULT_CAPILLARY, SCHEMES, common_grid, output_grid, validate_run

__all__ = ["simulate", "output_grid", "common_grid"]

def kernel_arguments(sched, resolved, strengths, pv_step):
    """``(prm, end_pv, inj, flow, out_pv)`` of ``run_kernel`` for a validated schedule, resolved parameters and
    effect strengths: the parameter vector, the slug ends (the last one the end of the output grid), the injected
    concentrations ``inj[4, slugs]``, the per-slug Darcy velocity and time per PV ``flow[2, slugs]`` and the output
    grid."""
    arrays = sched.kernel_arrays()
    inj = np.ascontiguousarray(np.vstack([arrays["c3"], arrays["c4"], arrays["c5"], arrays["c6"]]))
    out_pv = output_grid(sched.total_pv, pv_step)
    end_pv = arrays["end_pv"].copy()
    end_pv[-1] = out_pv[-1]
    # an output time that is a slug end up to rounding (140 x 0.01 = 1.4000000000000001, 0.6 + 0.8 = 1.4) is that
    # end, so its record holds the ending slug's values like every slug end's (the left limit), not the next slug's
    # after a rate step
    tol = 1.0e-9 * max(1.0, float(out_pv[-1]))
    near = np.abs(out_pv[:, None] - end_pv[None, :]) <= tol
    hit = near.any(axis=1)
    out_pv[hit] = end_pv[near.argmax(axis=1)[hit]]
    flow = slug_flow(resolved, sched.rates_ml_min(resolved["QINJ"]))
    return build_kernel_params(resolved, strengths), end_pv, inj, flow, out_pv


def switch_record(capillary, switch_pv, switch_at, switch_step, max_steps, pc_on):
    """The attrs ``capillary_implicit_from_pv`` (PV of the first implicit capillary step of the budgeted mode, NaN
    if it took none) and ``capillary_switch`` (why and where, or why not) of a run."""
    from .kernel import BUDGET_EXPLICIT_SHARE, BUDGET_IMPLICIT_SHARE

    rule = (f"at step {switch_at} of max_steps = {max_steps} ({BUDGET_EXPLICIT_SHARE:g} of the step budget used, "
            f"the explicit diffusion limit setting the step) the capillary mode switched to the implicit step "
            f"wherever the explicit one is below the switch step, {switch_step:.3g} PV then (the remaining PV in "
            f"{BUDGET_IMPLICIT_SHARE:g} of the remaining steps, recomputed every step)")
    if switch_pv >= 0.0:
        text = f"explicit capillary flux until {switch_pv:.6g} PV, the first implicit capillary step: {rule}"
        return {"capillary_implicit_from_pv": float(switch_pv), "capillary_switch": text}
    if switch_at >= 0:
        text = f"none: {rule}, but the explicit step never fell below it (the run is the explicit one)"
    elif capillary != "budgeted":
        text = (f"none: only capillary = 'budgeted' switches (this run: {capillary!r}, its implicit capillary steps "
                f"in n_capillary_implicit)")
    elif not pc_on:
        text = "none: capillary pressure is off"
    else:
        text = (f"none: the explicit flux throughout (its diffusion limit did not set a step after "
                f"{BUDGET_EXPLICIT_SHARE:g} of max_steps = {max_steps})")
    return {"capillary_implicit_from_pv": float("nan"), "capillary_switch": text}


def simulate(schedule, params=None, *, cells=100, effects=None, scheme="tvd", pv_step=0.01, profiles_at=None,
             cfl=0.5, permeability=None, alpha_t_ratio=None, pressure_every=None, pressure_solver=None,
             max_steps=None, max_wall_s=None, capillary=DEFAULT_CAPILLARY):
    """Run one SP coreflood and return an ``xarray.Dataset``.

    Parameters
    ----------
    schedule:
        ``"BCF1"``, ``"BCF2"``, ``"BCF3"`` (thesis Table 2.5), a ``Schedule``, or a list of slug mappings
        ``{"pv", "salinity_ppm", "surfactant_ppm", "polymer_ppm", "name", "rate_ml_min"}``. A slug's
        ``rate_ml_min`` (default: QINJ) is its injection rate: the outputs stay on injected PV, and ``dp`` and the
        rate-dependent physics (shear thinning, trapping number, capillary and molecular diffusion, kinetic
        adsorption per PV) follow the rate of the slug being injected (at a slug end: the ending slug's). 1-D only.
    params:
        UTCHEM-named parameters overriding the defaults (``spflow list params``; ``parameters.PARAMETERS``).
    cells:
        number of grid cells along the core (3 ... 20000); a pair ``(nx, ny)`` runs the 2-D model
        (``two_d.simulate2d``, thesis sec. 1.8), as does giving one of its arguments ``permeability`` (mD, shape
        ``(ny, nx)``), ``alpha_t_ratio`` (transverse/longitudinal dispersivity), ``pressure_every`` or
        ``pressure_solver`` (``"pcg"``, default, or ``"direct"``).
    effects:
        ``{effect name: strength}`` overriding the default strengths (``effects.BUILTIN_EFFECTS`` and plugins).
    scheme:
        ``"tvd"`` (second-order MUSCL, van Leer limiter; ``cfl <= 0.5``) or ``"upwind"`` (first order, ``cfl <= 1``).
    pv_step:
        spacing of the output ``pv`` grid; the grid runs from 0 to the total injected PV (appended if off-grid).
    profiles_at:
        injected PVs at which to return profiles on (``profile_pv``, ``x``).
    cfl:
        Courant number of the explicit transport step.
    max_steps, max_wall_s:
        step and wall-time budgets of the run (1-D only; ``budgets`` module): ``None`` is 50 x the expected steps
        ``ceil(total_pv * cells * 4 / cfl)`` and 600 s. Exceeding either raises ``SimulationError``.
    capillary:
        time discretisation of the capillary flux when the ``capillary_pressure`` effect is on, and the step
        control past half the step budget (1-D only): ``"budgeted"`` (default: the explicit scheme, bit for bit, in
        every run that finishes within half its step budget; past that, the budget step -- the remaining PV in half
        the remaining steps -- is the adaptive rule's switch step from the first step the explicit diffusion limit
        sets, and waves faster than it allows of a phase near its residual (oil, water or microemulsion) take the
        implicit release, with or without Pc; recorded in the attrs ``capillary_implicit_from_pv``,
        ``capillary_switch``, ``n_oil_release_implicit``, ``n_non_oleic_release_implicit`` and
        ``oil_release_implicit_from_pv``), ``"explicit"`` (forward Euler with the
        step limit ``dx^2 / (2 max D_cap)`` and the full wave-speed CFL on every step, however many steps it takes),
        ``"implicit"`` (linearised backward Euler, operator split after the advection, no step limit of its own)
        or ``"adaptive"`` (the explicit flux while its step limit is at least the CFL step of a wave of 100 PV^-1,
        25 x the speed of the budget's expected steps; the implicit step at that step where the explicit one would
        be shorter, so capillarity never costs more than half the default step budget). Against a time-converged
        reference the implicit and adaptive modes are less accurate than the explicit flux on strongly capillary
        BCF runs (docs/forward_model.md, "Capillary time step"); the budgeted mode is the explicit flux there. Only
        the budgeted mode acts with Pc off (its release); 2-D runs (no capillary flux, no step budget) accept
        ``"budgeted"`` and ``"explicit"``.

    Returns
    -------
    Dataset with ``dp`` (Pa), ``oil_cut``, ``recovery`` (fraction of OOIP), ``c_polymer_out``, ``c_surfactant_out``
    and ``salinity_out`` (ppm) on ``pv``; optional profiles ``sw``, ``so``, ``sme``, ``c_polymer``,
    ``c_surfactant``, ``salinity``, ``pressure`` (plus ``surfactant_adsorbed``, ``polymer_adsorbed`` and
    ``oil_overall`` for balances, and ``ift``); attrs with the schedule, grid, scheme, every resolved parameter
    (``param_<NAME>``) and effect strength (``effect_<name>``), the per-component relative mass-balance error,
    ``n_steps``, ``wall_time_s``, the budgets ``max_steps`` and ``max_wall_s`` and the step-control counts
    ``n_halvings`` (retried steps), ``n_capillary_limited`` (steps whose step the capillary term set: the
    saturation-change limit of the implicit step, the switch step of the adaptive mode, the diffusion limit of the
    explicit flux), ``n_ramp_limited`` (steps capped by the ramp after a slug start) and ``n_capillary_implicit``
    (steps taken with the implicit capillary step), ``capillary_implicit_from_pv`` (the PV of the budgeted mode's
    first implicit capillary step; NaN if it took none), ``capillary_switch`` (why and where, or why not),
    ``n_oil_release_implicit`` (cell-steps of the budgeted mode's implicit release of oil),
    ``n_non_oleic_release_implicit`` (of the aqueous or microemulsion phase near its residual) and
    ``oil_release_implicit_from_pv`` (the PV of the first release of either kind; NaN if none) (and
    ``slug_rate_ml_min``, the rate of every slug, when a slug sets its own).

    Adsorption in PV units: for a step injection of concentration ``C_J`` the Langmuir retardation is
    ``D = C^(C_J) / C_J = a / (1 + b C_J)`` pore volumes with ``a = AD41 + AD42 C_SEP`` and ``b = B4D`` for polymer
    (``C_J`` in wt %), ``a = AD31 + AD32 C_SE`` and ``b = B3D`` for surfactant (volume fraction); with the
    polymer storage ``EPHI4 S C`` the single-phase effluent midpoint is at ``EPHI4 + D`` PV.

    Raises
    ------
    ValueError (``ParameterError``) for invalid input, before any work; ``SimulationError`` if the run fails.
    """
    two_d = {"permeability": permeability, "alpha_t_ratio": alpha_t_ratio, "pressure_every": pressure_every,
             "pressure_solver": pressure_solver}
    if isinstance(cells, (tuple, list)) or any(v is not None for v in two_d.values()):
        from .two_d.simulate2d import simulate2d

        if max_steps is not None or max_wall_s is not None:
            raise ParameterError("max_steps and max_wall_s are available in 1-D runs only (cells an integer, no "
                                 "2-D arguments)")
        if capillary not in ("budgeted", "explicit"):
            raise ParameterError(f"capillary = {capillary!r} is available in 1-D runs only (cells an integer, no 2-D "
                                 "arguments); 2-D runs have no capillary flux and accept 'budgeted' or 'explicit'")

        return simulate2d(schedule, params, cells=cells, effects=effects, scheme=scheme, pv_step=pv_step,
                          profiles_at=profiles_at, cfl=cfl, **{k: v for k, v in two_d.items() if v is not None})
    if not isinstance(capillary, str) or capillary not in CAPILLARY:
        raise ParameterError(f"capillary must be one of {sorted(CAPILLARY)}, got {capillary!r}")
    sched, resolved, strengths, registry, cells, pv_step, prof, cfl = validate_run(
        schedule, params, cells, effects, scheme, pv_step, profiles_at, cfl
    )
    max_steps, max_wall_s = resolve_budgets(max_steps, max_wall_s, sched.total_pv, cells, cfl)
    from .kernel import ST_CAPILLARY, ST_HALVINGS, ST_IMPLICIT, ST_RAMP, run_kernel  # numba: imported at a run
    from .kernel import ST_RELEASE, ST_RELEASE_NON_OLEIC, ST_RELEASE_PV, ST_SWITCH_AT, ST_SWITCH_PV, ST_SWITCH_STEP
    from .outputs import build_dataset

    prm, end_pv, inj, flow, out_pv = kernel_arguments(sched, resolved, strengths, pv_step)
    start = time.perf_counter()
    with wall_clock_flag(max_wall_s) as stop:
        status, info, n_steps, series, profiles, totals, stats = run_kernel(
            prm, end_pv, inj, flow, out_pv, prof, cells, SCHEMES[scheme], cfl, max_steps, stop,
            CAPILLARY[capillary]
        )
    wall = time.perf_counter() - start
    if status != L.OK:
        budget = {L.ERR_STEPS: f"max_steps = {max_steps}", L.ERR_WALL: f"max_wall_s = {max_wall_s:g} s"}
        raise SimulationError(status, info, cells, budget.get(status))

    attrs = {"schedule": sched.name, "cells": cells, "scheme": scheme, "capillary": capillary, "cfl": cfl,
             "pv_step": pv_step,
             "n_steps": int(n_steps), "wall_time_s": wall, "max_steps": max_steps, "max_wall_s": max_wall_s,
             "n_halvings": int(stats[ST_HALVINGS]), "n_capillary_limited": int(stats[ST_CAPILLARY]),
             "n_ramp_limited": int(stats[ST_RAMP]), "n_capillary_implicit": int(stats[ST_IMPLICIT])}
    attrs.update(switch_record(capillary, stats[ST_SWITCH_PV], int(stats[ST_SWITCH_AT]), stats[ST_SWITCH_STEP],
                               max_steps, prm[K.PC0] > 0.0))
    attrs["n_oil_release_implicit"] = int(stats[ST_RELEASE] - stats[ST_RELEASE_NON_OLEIC])
    attrs["n_non_oleic_release_implicit"] = int(stats[ST_RELEASE_NON_OLEIC])
    attrs["oil_release_implicit_from_pv"] = float(stats[ST_RELEASE_PV]) if stats[ST_RELEASE] > 0 else float("nan")
    if sched.has_rates:
        attrs["slug_rate_ml_min"] = [float(r) for r in sched.rates_ml_min(resolved["QINJ"])]
    attrs.update({f"param_{k}": v for k, v in resolved.items()})
    attrs.update({f"effect_{k}": v for k, v in strengths.items()})
    ds = build_dataset(series, profiles, totals, out_pv, prof, cells, attrs)
    for name, s in strengths.items():
        effect = registry[name]
        if name not in E.BUILTIN_NAMES and effect.transform_output is not None:
            ds = effect.transform_output(ds, s)
    return ds
