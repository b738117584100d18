"""The 2-D IMPES time loop (thesis sec. 1.6): Python drives the steps, compiled functions do the per-cell work.

Per step (time in PV, the units of ``grid2d``):

1. local physics of every cell (``cell_properties`` on the flattened grid: the 1-D property passes, cell by cell);
2. implicit pressure (``pressure2d``: sparse two-point system, LU-preconditioned CG or ``splu``) and the face
   velocities -- every step with ``pressure_every = 1`` (IMPES), else every ``pressure_every`` steps and at every
   landed time (slug ends, profile times) and at the end of a step that passed an output time, the transport in
   between using the last velocity field
   (divergence-free, so still conservative); the lagged inputs of the next step's properties are made local:
   ``k|grad p| = |U| u_ref / lambda_T`` (trapping number) and the carrier flux scaled by ``|U| / sqrt(k / k_ref)``
   (the in-situ shear rate ``gamma_c |u_c| / sqrt(k k_r phi S)``);
3. records: the series at every output time passed by the last step (dense output, ``output_records``), maps at
   the profile times, which the step lands on;
4. time step from ``transport2d.stable_step``, capped by the ramp from every slug start (``kernel.ramp_step``),
   shortened to land on slug ends and profile times (never on output times), halved while any
   component would turn negative (``kernel.first_negative``; 60 halvings, then a time-step collapse);
5. explicit conservative advection (``transport2d``: TVD along rows and columns), then the split backward-Euler
   dispersion (``dispersion2d``).

Returns ``(status, info, n_steps, solver, series, maps, totals, pressure)`` with the 1-D kernel's conventions
(series rows ``output_records.DP ...``, profile rows ``kernel.P_*`` on the flattened grid, ``totals[4, 6]``), the
``PressureSolver`` (its counters ``n_solves``, ``n_factorizations``, ``n_iterations``) and the final pressure
field.
"""

from __future__ import annotations

import numpy as np

from .. import kernel as KR
from .. import kernel_inputs as K
from .. import output_records as R
from .. import state_layout as L
from .. import transport as T
from .dispersion2d import directional_coefficients, dispersion_step
from .grid2d import Grid2D
from .pressure2d import PressureSolver
from .transport2d import advective_fluxes_2d, conservative_update, outlet_rates, stable_step

__all__ = ["run_kernel2d"]


def _localise_lagged(st, field, kappa_flat):
    """Step 2: local k|grad p| and carrier flux for the trapping number and shear rate of the next step."""
    uc = 0.5 * (field.ux[:, :-1] + field.ux[:, 1:])
    vc = 0.5 * (field.vy[:-1, :] + field.vy[1:, :])
    speed = np.hypot(uc, vc).ravel()
    st[L.GRADK] *= speed
    st[L.FPC] *= speed / np.sqrt(kappa_flat)


def run_kernel2d(prm, end_pv, inj, out_pv, prof_pv, grid: Grid2D, tvd, cfl, alpha_t_ratio, pressure_every=1,
                 pressure_solver="pcg"):
    """Run the 2-D coreflood (arguments as ``kernel.run_kernel`` with the grid instead of the cell count, plus the
    transverse dispersivity ratio, the pressure frequency and ``pressure2d`` method); returns the tuple of the module
    docstring."""
    nx, ny, n = grid.nx, grid.ny, grid.n
    dx, dy = grid.dx, grid.dy
    n_out, n_prof, n_slug = out_pv.shape[0], prof_pv.shape[0], end_pv.shape[0]
    t_end = end_pv[-1]
    kappa_flat = np.ascontiguousarray(grid.kappa.ravel())
    pa_per_scaled = prm[K.UT] * prm[K.LENGTH] / prm[K.PERM_M2]
    st = np.zeros((L.NST, n))
    pr = np.zeros((L.NPR, n))
    fx = np.zeros((T.NFLUX, ny, nx + 1))
    gy = np.zeros((T.NFLUX, ny + 1, nx))
    new = np.zeros((6, n))
    d_stor = np.zeros((KR.N_DISP, n))
    d_stor[KR.D_SURF] = prm[K.EPHI3]
    d_conc = np.zeros((KR.N_DISP, n))
    d_coef = np.zeros((KR.N_DISP, n))
    coef_x = np.zeros((KR.N_DISP, n))
    coef_y = np.zeros((KR.N_DISP, n))
    m = max(nx, ny)
    work_c = np.zeros((KR.N_DISP, m))
    work_d = np.zeros((KR.N_DISP, m))
    jd = np.zeros((KR.N_DISP, m + 1))
    press = np.zeros(n)
    series = np.zeros((R.N_SERIES, n_out))
    maps = np.zeros((KR.N_PROFILE, n_prof, n))
    totals = np.zeros((4, 6))
    info = np.zeros(KR.N_INFO)
    cum = np.zeros(R.N_CUM)  # cumulative produced amounts (output_records), at t, t_prev and the last output
    cum_prev = np.zeros(R.N_CUM)
    cum_last = np.zeros(R.N_CUM)
    delta = np.zeros(R.N_CUM)
    rates = np.zeros(R.N_CUM)

    swi = prm[K.SWI]
    st[L.M1] = swi
    st[L.M2] = 1.0 - swi
    st[L.M5] = swi * prm[K.C50]
    st[L.M6] = swi * prm[K.C60]
    st[L.RK] = 1.0
    totals[0] = st[:6].sum(axis=1) / n
    ooip = 1.0 - swi
    dispersion = prm[K.ALPHA_D] + prm[K.ALPHA_D + 1] + prm[K.ALPHA_D + 2] + prm[K.DMOL] > 0.0
    solver = PressureSolver(grid, pressure_solver)

    t = t_prev = t_last = dp_prev = ramp = 0.0
    k_out = k_prof = slug = steps = 0
    dt_s = 0.0
    field = None
    status = KR.update_properties(st, pr, prm, n, 0.0, info, t)
    if status == L.OK:
        field = solver.solve(pr[L.LAMT].reshape(ny, nx))
        _localise_lagged(st, field, kappa_flat)
    since_solve = 0
    land = True  # solve at the first step (t = 0 is a landed time)
    while status == L.OK:
        status = KR.update_properties(st, pr, prm, n, dt_s, info, t)
        if status != L.OK:
            break
        if since_solve + 1 >= pressure_every or land or (k_out < n_out and out_pv[k_out] <= t):
            field = solver.solve(pr[L.LAMT].reshape(ny, nx))
            since_solve = 0
        else:
            since_solve += 1
        _localise_lagged(st, field, kappa_flat)
        ux, vy = field.ux, field.vy

        # ---- records: the series at t = 0 from the initial state, later every output time the last step passed
        dp_now = field.p_well * pa_per_scaled
        if steps == 0:
            advective_fluxes_2d(pr, nx, ny, ux, vy, False, 0.0, 0.0, 1.0, 1.0, 0.0, 0.0, 0.0, 0.0, fx, gy)
            outlet_rates(pr, fx, ux, nx, ny, nx, rates)
            total = rates[T.FW] + rates[T.FO] + rates[T.FS]  # the produced volume rate
            snap = rates / total if total > 0.0 else rates
            while k_out < n_out and out_pv[k_out] <= 0.0:
                series[R.DP, k_out] = dp_now
                series[R.RECOVERY, k_out] = 0.0
                series[R.OIL_CUT, k_out] = snap[T.FO]
                series[R.CS_OUT, k_out] = snap[T.FS]
                series[R.CP_OUT, k_out] = snap[T.FP] / snap[R.CARRIER] if snap[R.CARRIER] > 0.0 else 0.0
                series[R.SAL_OUT, k_out] = (snap[T.FA] / snap[T.FW] if snap[T.FW] > 0.0
                                            else pr[L.C5, nx - 1::nx].mean())
                k_out += 1
        else:
            k_out, t_last = R.record_outputs(series, out_pv, k_out, t_prev, t, dp_prev, dp_now, cum_prev, cum,
                                             cum_last, t_last, ooip, pr[L.C5, nx - 1::nx].mean(), delta)
        while k_prof < n_prof and t >= prof_pv[k_prof]:
            KR.record_profile(st, pr, prm, n, maps, k_prof, press)
            maps[KR.P_PRES, k_prof] = field.p.ravel() * pa_per_scaled  # the 2-D pressure, not the 1-D integral
            k_prof += 1
        if t >= t_end:
            break

        # ---- time step
        while slug < n_slug - 1 and t >= end_pv[slug]:
            slug += 1
            ramp = 0.0
        dt, ramp = KR.ramp_step(stable_step(pr, ux, vy, nx, ny, dx, dy, cfl), ramp, min(dx, dy), cfl)
        dt, land, next_stop = KR.landing_step(dt, t, end_pv[slug], prof_pv, k_prof)
        t_prev, dp_prev = t, dp_now
        cum_prev[:] = cum

        # ---- explicit advection, halving the step until no component goes negative
        bad = -1
        for _ in range(KR.MAX_HALVINGS):
            advective_fluxes_2d(pr, nx, ny, ux, vy, tvd, dt / dx, dt / dy, prm[K.EPHI3], prm[K.EPHI4], inj[0, slug],
                                inj[1, slug], inj[2, slug], inj[3, slug], fx, gy)
            conservative_update(st, fx, gy, ux, vy, nx, ny, dt, dx, dy, new)
            bad = KR.first_negative(new, st, n)
            if bad < 0:
                break
            dt *= 0.5
            land = False
        if bad >= 0:
            KR.fill_failure_info(info, t, bad, st, pr, dt)
            status = L.ERR_COLLAPSE
            break
        KR.polymer_storage(st, new, pr, prm[K.EPHI4], n, d_stor)
        st[:6] = new

        # ---- dispersion (split backward Euler, conservative)
        if dispersion:
            directional_coefficients(pr, prm, ux, vy, nx, ny, alpha_t_ratio, coef_x, coef_y)
            dispersion_step(st, pr, prm[K.EPHI3], nx, ny, dt, dx, dy, d_stor, d_conc, d_coef, coef_x, coef_y,
                            work_c, work_d, jd)

        # ---- bookkeeping
        outlet_rates(pr, fx, ux, nx, ny, 0, rates)
        totals[1] += rates[:6] * dt
        outlet_rates(pr, fx, ux, nx, ny, nx, rates)
        totals[2] += rates[:6] * dt
        cum += rates * dt
        t = next_stop if land else t + dt
        dt_s = dt * prm[K.T_PV]
        steps += 1
        bad = KR.first_nonfinite_cell(st, n)
        if bad >= 0:
            KR.fill_failure_info(info, t, bad, st, pr, dt)
            status = L.ERR_NONFINITE

    totals[3] = st[:6].sum(axis=1) / n
    return status, info, steps, solver, series, maps, totals, field
