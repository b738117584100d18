"""The compiled IMPES time loop: one ``@njit`` function running a whole coreflood on preallocated arrays.

Per step (all in pore-volume units, see ``transport``):

1. local physics of every cell from the conserved state (``cell_properties``: adsorption, flash, viscosities, IFT,
   trapping, mobilities);
2. records: the series at every output time passed by the last step, by dense output (``output_records``: exact
   effluent averages from cumulative amounts, pressure drop interpolated), and profiles at the profile times, which
   the step lands on;
3. pressure: incompressible flow at a constant injection rate with the producer at constant pressure makes the
   total Darcy velocity uniform, so the implicit pressure equation reduces to the integral of ``u / (k lambda_T)``
   over the cells (with Pc on: the global pressure) -- ``transport.pressure_profile``;
4. time step: ``dt = cfl dx / max_i speed_i`` (advective CFL from the local wave-speed bound); with Pc, by the
   capillary mode (``state_layout.CAP_*``): the explicit flux adds the diffusion limit ``+ 2 max_i D_cap,i / dx^2``
   to the rate; the implicit step is at most the step at which the step-start capillary fluxes change a cell's
   water volume by ``CAPILLARY_DS_MAX``, but not below ``CAPILLARY_MIN_FRACTION`` of the advective step (an accuracy
   limit: it needs none for stability); the adaptive mode takes the explicit step while its diffusion limit is at
   least the CFL step of a wave of speed ``CAPILLARY_SWITCH_SPEED`` (the switch step), and else the implicit step at
   the switch step (or the advective step if that is shorter); the budgeted mode is the explicit scheme until
   ``BUDGET_EXPLICIT_SHARE`` of the step budget is used; from then on the budget step -- the remaining PV in
   ``BUDGET_IMPLICIT_SHARE`` of the remaining steps, recomputed every step, never below its value at the share --
   is the adaptive mode's switch step (from the first step the diffusion limit sets), and release-phase wave speeds
   above the budget step's CFL speed leave the step to the other speeds and take the implicit release
   (``transport.implicit_release_fluxes``: linearised backward-Euler upwind outflow of the cells whose Courant
   number of the phase with the largest mobility derivative -- oil, water or microemulsion near its residual --
   exceeds ``cfl``). The step is capped by a ramp
   from every slug start (``ramp_step``:
   the cell states do not yet span the wave that the newly injected fluid makes, so their speeds underestimate it),
   shortened to land exactly on slug ends and profile times. Output times never shorten a step, so the series do
   not depend on the output grid;
5. explicit conservative update of the six components with the TVD (or upwind) fluxes (the released cells' outflow
   faces replaced, budgeted mode past its share) (plus the explicit
   capillary fluxes), or, on an implicit capillary step, the advective update followed by the linearly implicit
   capillary step (``capillary_step``: backward Euler in the carrier saturation, operator split, conservative;
   ``transport.implicit_capillary_fluxes``); a step that would make a saturation or concentration
   negative beyond round-off is retried with half the step, and fails as a time-step collapse after 60 halvings;
6. backward-Euler dispersion of surfactant, polymer, anions and divalent cations (operator split, conservative),
   the four tridiagonal systems solved in one batched sweep (``transport.solve_dispersion``).

Budgets: before each step the loop stops with ``ERR_STEPS`` once ``max_steps`` steps are done and with ``ERR_WALL``
once ``stop[0]`` is non-zero (set from another thread by ``simulate``'s wall-time watchdog: the kernel releases the
GIL, numba has no clock); the failing cell reported is the one that limits the next step.

Returns ``(status, info, n_steps, series, profiles, totals, stats)``; ``status`` is a ``state_layout`` error code and
``info = [pv, cell, M1..M6, S1, S2, S3, dt]`` describes the failing cell; ``stats[N_STATS]`` counts the step
halvings (``ST_HALVINGS``), the steps whose step was set by the capillary term rather than the wave speed
(``ST_CAPILLARY``: the saturation-change limit of the implicit step, or the diffusion limit of the explicit one),
the steps capped by the ramp (``ST_RAMP``) and the steps taken with the implicit capillary step (``ST_IMPLICIT``);
in the budgeted mode the step count at which it switched to the adaptive rule (``ST_SWITCH_AT``, -1 if it did not),
the budget step at the share (``ST_SWITCH_STEP``, PV), the time of its first implicit capillary step
(``ST_SWITCH_PV``, -1 if it took none), the cell-steps of the implicit release (``ST_RELEASE``; of them in the
aqueous or microemulsion phase: ``ST_RELEASE_NON_OLEIC``) and the time of the first (``ST_RELEASE_PV``, -1 if
none); a budgeted run with neither is the explicit run.
``totals[4, 6]`` holds, per component, the amount in place at the start, injected, produced and in place at the end
(PV units), for the mass balance.
"""

import math

import numpy as np
from numba import njit

from . import kernel_inputs as K
from . import output_records as R
from . import state_layout as L
from . import transport as T
from .cell_properties import cell_properties

# profile rows
P_SW, P_SO, P_SME, P_CP, P_CS, P_SAL, P_PRES, P_ADS3, P_ADS4, P_OIL, P_IFT = range(11)
N_PROFILE = 11
N_INFO = 12
# stats rows
(ST_HALVINGS, ST_CAPILLARY, ST_RAMP, ST_IMPLICIT, ST_SWITCH_PV, ST_SWITCH_AT, ST_SWITCH_STEP, ST_RELEASE,
 ST_RELEASE_PV, ST_RELEASE_NON_OLEIC) = range(10)
N_STATS = 10
# dispersion rows
D_ANION, D_DIVALENT, D_SURF, D_POLY = range(4)
N_DISP = 4

NEG_TOL = 1.0e-10
MAX_HALVINGS = 60
# step ramp from every slug start: the first step is the CFL step of a wave of speed RAMP_SPEED (PV units, above any
# fractional-flow slope of the model's relative permeabilities), each later one at most RAMP_GROWTH times the last
RAMP_SPEED = 16.0
RAMP_GROWTH = 1.25
# accuracy control of the implicit capillary step (stability needs none): the capillary flux of the step-start
# state may change a cell's water volume by at most CAPILLARY_DS_MAX per step (the saturation-change limit of
# production simulators, e.g. ECLIPSE's DSMAX), but it shortens the advective step by at most the factor
# CAPILLARY_MIN_FRACTION: in a capillary-dominated flood the explicit fluxes overestimate the change the implicit
# step makes (it stops at capillary equilibrium); docs/forward_model.md has the measured time error
CAPILLARY_DS_MAX = 0.05
CAPILLARY_MIN_FRACTION = 0.05
# the adaptive capillary mode takes the explicit flux while its diffusion-limited step is at least the CFL step of a
# wave of this speed (PV units), the switch step: 25 x the wave speed of the step budget's expected steps
# (budgets.expected_steps), so the capillary term costs at most half the default budget; where the explicit step
# would be shorter, the implicit capillary step at the switch step
CAPILLARY_SWITCH_SPEED = 100.0
# the budgeted mode (the default) is the explicit scheme, bit for bit, in every run that finishes within
# BUDGET_EXPLICIT_SHARE of its step budget; past it, the budget step fits the remaining PV into
# BUDGET_IMPLICIT_SHARE of the remaining steps (recomputed every step, never below its value at the share, so it
# grows where other limits use up steps): the capillary switch step from the first step the explicit diffusion
# limit sets, and the step below which fast waves of a phase near its residual are released implicitly
BUDGET_EXPLICIT_SHARE = 0.5
BUDGET_IMPLICIT_SHARE = 0.5


@njit(cache=True, error_model="numpy")
def update_properties(st, pr, prm, n, dt_s, info, t):
    """The properties ``pr`` of every cell from the state ``st`` (:func:`cell_properties`, shared with the 2-D
    kernel); on failure the failing cell's state is written to ``info`` (:func:`fill_failure_info`). Returns the status
    code (``state_layout.OK`` or the failure)."""
    code, i = cell_properties(st, pr, prm, n, dt_s)
    if code != L.OK:
        fill_failure_info(info, t, i, st, pr, 0.0)
    return code


@njit(cache=True, error_model="numpy")
def fill_failure_info(info, t, i, st, pr, dt):
    """What ``SimulationError`` reports of a failed run: time ``t``, cell ``i``, its six conserved amounts, its
    three saturations and the step ``dt``, into ``info[:12]``."""
    info[0] = t
    info[1] = i
    for r in range(6):
        info[2 + r] = st[r, i]
    for l in range(3):
        info[8 + l] = pr[L.S1 + l, i]
    info[11] = dt


@njit(cache=True, error_model="numpy")
def first_nonfinite_cell(st, n):
    """First cell with a non-finite conserved amount (rows M1..M6), or -1 (a branch-free scan first: the search
    only runs after a failure)."""
    finite = True
    for r in range(6):
        for i in range(n):
            finite &= math.isfinite(st[r, i])
    if finite:
        return -1
    for i in range(n):
        for r in range(6):
            if not math.isfinite(st[r, i]):
                return i
    return -1


@njit(cache=True, error_model="numpy")
def record_profile(st, pr, prm, n, prof, kp, press):
    """Profile ``kp`` (saturations, polymer, surfactant, salinity, pressure, adsorbed surfactant per cell) into
    ``prof``; the pressure from the current properties (``press`` is scratch)."""
    T.pressure_profile(pr, n, prm[K.LENGTH] / n, prm[K.UT], prm[K.PERM_M2], press)
    for i in range(n):
        prof[P_SW, kp, i] = pr[L.S1, i]
        prof[P_SO, kp, i] = pr[L.S1 + 1, i]
        prof[P_SME, kp, i] = pr[L.S1 + 2, i]
        prof[P_CP, kp, i] = pr[L.CP, i]
        prof[P_CS, kp, i] = st[L.M3, i] - st[L.A3, i]
        prof[P_SAL, kp, i] = pr[L.C5, i]
        prof[P_PRES, kp, i] = press[i]
        prof[P_ADS3, kp, i] = st[L.A3, i]
        prof[P_ADS4, kp, i] = st[L.A4, i]
        prof[P_OIL, kp, i] = st[L.M2, i]
        prof[P_IFT, kp, i] = pr[L.IFT, i]


@njit(cache=True, error_model="numpy")
def first_negative(new, st, n):
    """First cell whose updated water, oil, anions, divalent cations or fluid (non-adsorbed) surfactant or polymer
    ``new[6, n]`` is negative beyond ``NEG_TOL`` (``st`` holds the adsorbed amounts), or -1."""
    for i in range(n):
        if (new[L.M1, i] < -NEG_TOL or new[L.M2, i] < -NEG_TOL or new[L.M3, i] - st[L.A3, i] < -NEG_TOL
                or new[L.M4, i] - st[L.A4, i] < -NEG_TOL or new[L.M5, i] < -NEG_TOL
                or new[L.M6, i] < -NEG_TOL):
            return i
    return -1


@njit(cache=True, error_model="numpy")
def polymer_storage(st, new, pr, e4, n, d_stor):
    """Polymer storage after advection: ``EPHI4`` x carrier saturation, scaled with the water volume change."""
    for i in range(n):
        m1_old = st[L.M1, i]
        ratio = new[L.M1, i] / m1_old if m1_old > 0.0 else 1.0
        d_stor[D_POLY, i] = e4 * pr[L.SPC, i] * max(ratio, 0.0)


@njit(cache=True, error_model="numpy")
def dispersion_inputs(st, pr, e3, n, d_stor, d_conc, d_coef):
    """Storage, concentration and cell coefficient of the dispersed species (rows ``D_*``) of every cell; the
    polymer storage row is set by ``polymer_storage``."""
    for i in range(n):
        # anions and divalent cations per water volume (storage: water volume)
        m1 = st[L.M1, i]
        d_stor[D_ANION, i] = max(m1, 0.0)
        d_stor[D_DIVALENT, i] = d_stor[D_ANION, i]
        d_conc[D_ANION, i] = st[L.M5, i] / m1 if m1 > 0.0 else 0.0
        d_conc[D_DIVALENT, i] = st[L.M6, i] / m1 if m1 > 0.0 else 0.0
        # surfactant: overall accessible concentration, storage EPHI3
        d_conc[D_SURF, i] = max(st[L.M3, i] - st[L.A3, i], 0.0) / e3
        # polymer in its carrier phase
        s_p = d_stor[D_POLY, i]
        d_conc[D_POLY, i] = max(st[L.M4, i] - st[L.A4, i], 0.0) / s_p if s_p > 0.0 else 0.0
        d_coef[D_ANION, i] = pr[L.KW, i]
        d_coef[D_DIVALENT, i] = pr[L.KW, i]
        d_coef[D_SURF, i] = pr[L.KS, i]
        d_coef[D_POLY, i] = pr[L.KP, i]


@njit(cache=True, error_model="numpy")
def apply_dispersion(st, n, lamd, jd):
    """Conservative update of the dispersed species with the face fluxes ``jd`` of ``transport.solve_dispersion``."""
    for i in range(n):
        st[L.M5, i] -= lamd * (jd[D_ANION, i + 1] - jd[D_ANION, i])
        st[L.M6, i] -= lamd * (jd[D_DIVALENT, i + 1] - jd[D_DIVALENT, i])
        st[L.M3, i] -= lamd * (jd[D_SURF, i + 1] - jd[D_SURF, i])
        st[L.M4, i] -= lamd * (jd[D_POLY, i + 1] - jd[D_POLY, i])


@njit(cache=True, error_model="numpy")
def capillary_step(st, new, pr, prm, n, dx, lam, k_over_ul, ds_adv, work, cap_flux):
    """The implicit capillary part of a step (operator split after the advective update ``new``): the
    carrier-saturation change of the advection (water volume change over the carrier's water fraction), then the
    backward-Euler capillary face fluxes (``transport.implicit_capillary_fluxes``) applied conservatively to
    ``new``."""
    for i in range(n):
        pcx = int(pr[L.PCX, i])
        c1 = pr[L.C1P + pcx - 1, i] if pcx > 0 else 0.0
        ds_adv[i] = (new[L.M1, i] - st[L.M1, i]) / c1 if c1 > 0.0 else 0.0
    cap_flux[:] = 0.0
    T.implicit_capillary_fluxes(pr, n, dx, lam, k_over_ul, prm[K.PC0], prm[K.EPC0], prm[K.SIGOW], ds_adv, work,
                                cap_flux)
    for r in range(6):
        for i in range(n):
            new[r, i] -= lam * (cap_flux[r, i + 1] - cap_flux[r, i])


@njit(cache=True, error_model="numpy")
def capillary_change_step(pr, n, dx, k_over_ul, cap_flux):
    """The step at which the explicit capillary fluxes of the step-start state change some cell's water volume by
    ``CAPILLARY_DS_MAX`` (infinite if they change none): the accuracy limit of the implicit capillary step.
    ``cap_flux`` is scratch."""
    cap_flux[:] = 0.0
    T.capillary_fluxes(pr, n, dx, k_over_ul, cap_flux)
    rate = 0.0
    for i in range(n):
        rate = max(rate, abs(cap_flux[T.FW, i + 1] - cap_flux[T.FW, i]))
    return CAPILLARY_DS_MAX * dx / rate if rate > 0.0 else np.inf


@njit(cache=True, error_model="numpy")
def _limiting_cell(pr, n, dx, explicit_pc):
    """``(cell, rate)``: the cell whose step limit (wave speed, plus the explicit capillary diffusion) is the
    tightest, for the message of a run stopped by a budget."""
    rmax = 0.0
    limiting = 0
    for i in range(n):
        rate_i = pr[L.SPEED, i] / dx + (2.0 * pr[L.DCAP, i] / (dx * dx) if explicit_pc else 0.0)
        if rate_i > rmax:
            rmax = rate_i
            limiting = i
    return limiting, rmax


@njit(cache=True, error_model="numpy")
def ramp_step(dt_stable, ramp, dx, cfl):
    """The stable step capped by the ramp: ``ramp`` is the cap of the previous step (0 at a slug start, where the
    cap is the CFL step of a wave of speed ``RAMP_SPEED``); returns ``(dt, cap)`` with the cap for the next call.

    At a slug start the cells hold the states left by the previous fluid (at t = 0 the connate water, where
    df/dS = 0), so the wave speeds computed from them miss the wave the injected fluid is about to make (the
    Buckley-Leverett shock has speed f(S*)/(S* - S_wc) > 0); a step sized from them alone would push a piston-like
    first front into the core. The ramp lets the cells develop the states of the new wave first."""
    cap = cfl * dx / RAMP_SPEED if ramp <= 0.0 else ramp * RAMP_GROWTH
    return min(dt_stable, cap), cap


@njit(cache=True, error_model="numpy")
def landing_step(dt, t, slug_end, prof_pv, k_prof):
    """The stable step ``dt`` from time ``t`` shortened to land exactly on the next stop (the slug end or the next
    profile time), and halved when a full step would leave less than half a step before it; returns
    ``(dt, landed, stop)``: the time is set to ``stop`` exactly after a landed step (no round-off drift)."""
    next_stop = slug_end
    if k_prof < prof_pv.shape[0] and prof_pv[k_prof] < next_stop:
        next_stop = prof_pv[k_prof]
    remaining = next_stop - t
    if dt >= remaining:
        return remaining, True, next_stop
    if dt > 0.5 * remaining:
        return 0.5 * remaining, False, next_stop
    return dt, False, next_stop


@njit(cache=True, error_model="numpy", nogil=True)
def run_kernel(prm, end_pv, inj, flow, out_pv, prof_pv, n, tvd, cfl, max_steps, stop,
               capillary_mode=L.CAP_EXPLICIT):
    """Run the coreflood. ``inj[4, slugs]`` = surfactant vol. frac., polymer wt %, anions, divalent (meq/ml);
    ``flow[2, slugs]`` = Darcy velocity (m/s) and time per PV (s) of each slug (``kernel_inputs.slug_flow``);
    ``end_pv`` cumulative slug ends; ``out_pv`` output times (first 0, last the total PV); ``prof_pv`` sorted
    profile times; ``n`` cells; ``tvd`` True for the TVD scheme; ``cfl`` Courant number; ``max_steps`` the step
    budget; ``stop[1]`` the wall-time flag (non-zero: stop before the next step); ``capillary_mode`` the time
    discretisation of the capillary flux (``state_layout.CAP_EXPLICIT``: explicit fluxes with the diffusion step
    limit; ``CAP_IMPLICIT``: the linearly implicit capillary step on every step; ``CAP_ADAPTIVE``: explicit while
    the diffusion limit stays above the CFL step of a wave of speed ``CAPILLARY_SWITCH_SPEED``, implicit below;
    ``CAP_BUDGETED``: the explicit scheme until ``BUDGET_EXPLICIT_SHARE`` of ``max_steps`` is used, then the budget
    step as the adaptive switch step, from the first step the diffusion limit sets, and the implicit release where
    a release-phase wave is faster than the budget step allows -- with Pc off too).

    Each slug runs at its own rate: ``UT`` and ``T_PV`` of (a copy of) ``prm`` are those of the slug being injected,
    so the pressure drop, shear rate, trapping number, capillary and molecular-diffusion terms and the kinetic
    adsorption step see it; records at a slug end hold the ending slug's values (the left limit)."""
    prm = prm.copy()
    prm[K.UT] = flow[K.FLOW_UT, 0]
    prm[K.T_PV] = flow[K.FLOW_T_PV, 0]
    n_out = out_pv.shape[0]
    n_prof = prof_pv.shape[0]
    n_slug = end_pv.shape[0]
    t_end = end_pv[n_slug - 1]
    dx = 1.0 / n
    st = np.zeros((L.NST, n))
    pr = np.zeros((L.NPR, n))
    flux = np.zeros((T.NFLUX, n + 1))
    new = np.zeros((6, n))
    # dispersion: one batched solve of anions, divalent cations, surfactant and polymer (rows D_*)
    jd = np.zeros((N_DISP, n + 1))
    work_c = np.zeros((N_DISP, n))
    work_d = np.zeros((N_DISP, n))
    d_stor = np.zeros((N_DISP, n))
    d_stor[D_SURF] = prm[K.EPHI3]
    d_conc = np.zeros((N_DISP, n))
    d_coef = np.zeros((N_DISP, n))
    press = np.zeros(n)
    # capillary step: carrier-saturation change of the advection, solver scratch, capillary face fluxes
    ds_adv = np.zeros(n)
    cap_work = np.zeros((5, n + 1))
    cap_flux = np.zeros((T.NFLUX, n + 1))
    capillary = prm[K.PC0] > 0.0
    # whether the current (last) step takes the implicit capillary step (for the budget message before a step)
    implicit_step = capillary and capillary_mode == L.CAP_IMPLICIT
    switch_step = cfl * dx / CAPILLARY_SWITCH_SPEED
    # budgeted mode: from which step count the budget step applies, whether the capillary flux has switched to the
    # adaptive rule, the budget step (0 before the share) and the wave speed above which oil is released implicitly
    switch_after = BUDGET_EXPLICIT_SHARE * max_steps
    switched = False
    budget_step = 0.0
    release_speed = np.inf
    fc_out = -1.0
    series = np.zeros((R.N_SERIES, n_out))
    prof = np.zeros((N_PROFILE, n_prof, n))
    totals = np.zeros((4, 6))
    info = np.zeros(N_INFO)
    stats = np.zeros(N_STATS)
    stats[ST_SWITCH_PV] = -1.0
    stats[ST_SWITCH_AT] = -1.0
    stats[ST_RELEASE_PV] = -1.0
    cum = np.zeros(R.N_CUM)  # cumulative produced amounts (output_records), at t, t_prev and the last output
    cum_prev = np.zeros(R.N_CUM)
    cum_last = np.zeros(R.N_CUM)
    delta = np.zeros(R.N_CUM)

    swi = prm[K.SWI]
    for i in range(n):
        st[L.M1, i] = swi
        st[L.M2, i] = 1.0 - swi
        st[L.M5, i] = swi * prm[K.C50]
        st[L.M6, i] = swi * prm[K.C60]
        st[L.RK, i] = 1.0
    for r in range(6):
        for i in range(n):
            totals[0, r] += st[r, i] * dx
    ooip = (1.0 - swi)
    dispersion = prm[K.ALPHA_D] + prm[K.ALPHA_D + 1] + prm[K.ALPHA_D + 2] + prm[K.DMOL] > 0.0
    k_over_ul = prm[K.PERM_M2] / (prm[K.UT] * prm[K.LENGTH])

    t = 0.0
    t_prev = 0.0
    t_last = 0.0
    dp_prev = 0.0
    dp_now = 0.0
    k_out = 0
    k_prof = 0
    slug = 0
    ramp = 0.0
    steps = 0
    dt_s = 0.0
    # the first pass sets the lagged trapping and shear inputs (k|grad p|, carrier flux) of the initial state
    status = update_properties(st, pr, prm, n, 0.0, info, t)
    while status == L.OK:
        status = update_properties(st, pr, prm, n, dt_s, info, t)
        if status != L.OK:
            break
        # ---- records: the series at t = 0 from the initial state, later every output time the last step passed
        # (the pressure integral only at the two ends of a step that holds an output time)
        recording = steps == 0 or (k_out < n_out and out_pv[k_out] <= t)
        if recording:
            dp_now = T.pressure_profile(pr, n, prm[K.LENGTH] / n, prm[K.UT], prm[K.PERM_M2], press)
        if steps == 0:
            while k_out < n_out and out_pv[k_out] <= 0.0:
                T.advective_fluxes(pr, n, False, 0.0, 1.0, 1.0, 0.0, 0.0, 0.0, 0.0, flux)
                series[R.DP, k_out] = dp_now
                series[R.RECOVERY, k_out] = 0.0
                series[R.OIL_CUT, k_out] = flux[T.FO, n]
                series[R.CS_OUT, k_out] = flux[T.FS, n]
                series[R.CP_OUT, k_out] = pr[L.CP, n - 1] if pr[L.PCX, n - 1] > 0.0 else 0.0
                series[R.SAL_OUT, k_out] = pr[L.C5, n - 1]
                k_out += 1
        elif recording:
            k_out, t_last = R.record_outputs(series, out_pv, k_out, t_prev, t, dp_prev, dp_now, cum_prev, cum,
                                             cum_last, t_last, ooip, pr[L.C5, n - 1], delta)
        while k_prof < n_prof and t >= prof_pv[k_prof]:
            record_profile(st, pr, prm, n, prof, k_prof, press)
            k_prof += 1
        if t >= t_end:
            break

        # ---- time step
        while slug < n_slug - 1 and t >= end_pv[slug]:
            slug += 1
            ramp = 0.0
        if flow[K.FLOW_UT, slug] != prm[K.UT]:
            # a rate step: the new slug's velocity, and the local physics again at it (dt_s = 0: no kinetic
            # adsorption time passes); the outputs inside the next step start from the new rate's dp
            prm[K.UT] = flow[K.FLOW_UT, slug]
            prm[K.T_PV] = flow[K.FLOW_T_PV, slug]
            k_over_ul = prm[K.PERM_M2] / (prm[K.UT] * prm[K.LENGTH])
            status = update_properties(st, pr, prm, n, 0.0, info, t)
            if status != L.OK:
                break
        if steps >= max_steps or stop[0] != 0:
            limiting, rmax = _limiting_cell(pr, n, dx, capillary and not implicit_step)
            fill_failure_info(info, t, limiting, st, pr, cfl / rmax if rmax > 0.0 else 0.0)
            status = L.ERR_STEPS if steps >= max_steps else L.ERR_WALL
            break
        if capillary_mode == L.CAP_BUDGETED and steps >= switch_after:
            # the budget step: the remaining PV in BUDGET_IMPLICIT_SHARE of the remaining steps, never below its
            # value at the share; release-phase wave speeds above its CFL speed are taken by the implicit release
            step_b = (t_end - t) / (BUDGET_IMPLICIT_SHARE * (max_steps - steps))
            if budget_step == 0.0:
                stats[ST_SWITCH_STEP] = step_b
            budget_step = max(stats[ST_SWITCH_STEP], step_b)
            release_speed = cfl * dx / budget_step
        smax = 0.0
        dmax = 0.0
        for i in range(n):
            speed = pr[L.SPEED, i]
            if pr[L.WAVE_R, i] > release_speed:
                speed = max(pr[L.SPEED_X, i], release_speed)
            if speed > smax:
                smax = speed
            if capillary and capillary_mode != L.CAP_IMPLICIT and pr[L.DCAP, i] > dmax:
                dmax = pr[L.DCAP, i]
        rate = smax / dx + 2.0 * dmax / (dx * dx)
        dt_stable = cfl / rate if rate > 0.0 else np.inf
        if (capillary and capillary_mode == L.CAP_BUDGETED and not switched and steps >= switch_after
                and 2.0 * dmax / dx > smax):
            # the explicit diffusion limit would carry the run past its budget: the adaptive rule from here, at
            # the switch step that leaves (1 - BUDGET_IMPLICIT_SHARE) of the remaining steps to the wave speed
            switched = True
            stats[ST_SWITCH_AT] = steps
        if switched:
            switch_step = budget_step
        implicit_step = capillary and (capillary_mode == L.CAP_IMPLICIT
                                       or ((capillary_mode == L.CAP_ADAPTIVE or switched)
                                           and dt_stable < switch_step))
        if implicit_step:
            if switched and stats[ST_SWITCH_PV] < 0.0:
                stats[ST_SWITCH_PV] = t
            # the advective step, shortened by the saturation-change control (implicit mode) or to the switch step
            dt_stable = cfl / (smax / dx) if smax > 0.0 else np.inf
            if capillary_mode == L.CAP_IMPLICIT:
                dt_cap = max(capillary_change_step(pr, n, dx, k_over_ul, cap_flux),
                             CAPILLARY_MIN_FRACTION * dt_stable)
            else:
                dt_cap = switch_step
            if dt_cap < dt_stable:
                dt_stable = dt_cap
                stats[ST_CAPILLARY] += 1.0
            stats[ST_IMPLICIT] += 1.0
        elif 2.0 * dmax / dx > smax:
            stats[ST_CAPILLARY] += 1.0
        dt, ramp = ramp_step(dt_stable, ramp, dx, cfl)
        if dt < dt_stable:
            stats[ST_RAMP] += 1.0
        dt, land, next_stop = landing_step(dt, t, end_pv[slug], prof_pv, k_prof)
        t_prev = t
        if k_out < n_out and out_pv[k_out] <= (next_stop if land else t + dt):
            # an output inside this step: the pressure drop at its start (after any rate step), for the interpolation
            dp_prev = T.pressure_profile(pr, n, prm[K.LENGTH] / n, prm[K.UT], prm[K.PERM_M2], press)
        for r in range(R.N_CUM):
            cum_prev[r] = cum[r]

        # ---- fluxes and explicit update, halving the step until no component goes negative
        bad = -1
        n_release = 0
        n_release_non_oleic = 0
        for _ in range(MAX_HALVINGS):
            lam = dt / dx
            T.advective_fluxes(pr, n, tvd, lam, prm[K.EPHI3], prm[K.EPHI4], inj[0, slug], inj[1, slug],
                               inj[2, slug], inj[3, slug], flux)
            if budget_step > 0.0:  # (budget_step does not change across halvings: the counts are this try's)
                n_release, n_release_non_oleic, fc_out = T.implicit_release_fluxes(pr, n, lam, cfl, flux)
            if capillary and not implicit_step:
                T.capillary_fluxes(pr, n, dx, k_over_ul, flux)
            for r in range(6):
                for i in range(n):
                    new[r, i] = st[r, i] - lam * (flux[r, i + 1] - flux[r, i])
            if implicit_step:
                capillary_step(st, new, pr, prm, n, dx, lam, k_over_ul, ds_adv, cap_work, cap_flux)
            bad = first_negative(new, st, n)
            if bad < 0:
                break
            dt *= 0.5
            land = False
            stats[ST_HALVINGS] += 1.0
        if bad >= 0:
            fill_failure_info(info, t, bad, st, pr, dt)
            status = L.ERR_COLLAPSE
            break

        # polymer storage after advection: EPHI4 x carrier saturation, scaled with the water volume
        polymer_storage(st, new, pr, prm[K.EPHI4], n, d_stor)
        st[:6] = new

        # ---- dispersion (backward Euler, conservative)
        if dispersion:
            lamd = dt / (dx * dx)
            dispersion_inputs(st, pr, prm[K.EPHI3], n, d_stor, d_conc, d_coef)
            T.solve_dispersion(d_stor, d_conc, d_coef, n, lamd, work_c, work_d, jd)
            apply_dispersion(st, n, lamd, jd)

        if n_release > 0:
            stats[ST_RELEASE] += n_release
            stats[ST_RELEASE_NON_OLEIC] += n_release_non_oleic
            if stats[ST_RELEASE_PV] < 0.0:
                stats[ST_RELEASE_PV] = t

        # ---- bookkeeping
        pcx = int(pr[L.PCX, n - 1])
        f_c = pr[L.F1, n - 1] if pcx == 1 else (pr[L.F1 + 2, n - 1] if pcx == 3 else 0.0)
        if n_release > 0 and fc_out >= 0.0:
            f_c = fc_out  # the released outlet cell's carrier fraction
        for r in range(6):
            totals[1, r] += flux[r, 0] * dt
            totals[2, r] += flux[r, n] * dt
            cum[r] += flux[r, n] * dt
        cum[R.CARRIER] += f_c * dt
        t = next_stop if land else t + dt
        dt_s = dt * prm[K.T_PV]
        steps += 1
        bad = first_nonfinite_cell(st, n)
        if bad >= 0:
            fill_failure_info(info, t, bad, st, pr, dt)
            status = L.ERR_NONFINITE

    for r in range(6):
        for i in range(n):
            totals[3, r] += st[r, i] * dx
    return status, info, steps, series, prof, totals, stats
