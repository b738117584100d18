"""Local (per-cell) physics of one time step: adsorption, flash, viscosities, IFT, trapping, mobilities.

``cell_properties(st, pr, prm, n, dt_s)`` turns the conserved state of every cell (``state_layout``) into the
properties the transport step needs, calling the property kernels of ``physics/``:

1. salinity per water volume and effective salinities (Eq. 2.3; ``C_SE = C51/(1 - BETA6 f6s)``);
2. surfactant adsorption from the total surfactant (Eqs. 2.15-2.16, storage scaled by EPHI3), irreversible
   (running maximum) and optionally first-order kinetic -- ``adsorbed_amount``;
3. Hand's-rule flash of the overall fluid composition (water, oil, accessible surfactant), normalised to 1;
4. polymer in its carrier phase (the phase holding most of the water: aqueous, or the water-rich microemulsion of a
   type II(-) system) with storage ``EPHI4 S_c C4`` (scaled IPV) plus adsorption (irreversible, or with a reversible
   fraction -- ``partly_reversible_adsorbed``), and the irreversible permeability reduction (Eqs. 2.7-2.8, running
   maximum of R_k);
5. polymer-solution viscosity (Eqs. 2.1-2.2) with Meter shear thinning (Eq. 2.4) at the in-situ shear rate of the
   previous step, GAMHF fixed or Eq. 2.5; phase viscosities by Eq. 2.11 (the polymer solution replaces water in the
   carrier phase);
6. IFTs by Chun-Huh with Hirasaki's correction (Eqs. 2.9-2.10) and, for each phase, the trapping number against its
   conjugate phase ``N_T = k|grad p| / sigma`` with ``k|grad p| = u / lambda_T`` of the previous step (1-D, no
   gravity), residuals (Eq. 2.12, tau = 1), end points and exponents (Eq. 2.13), Corey rel-perms (Eq. 2.14);
7. fractional flows, a bound on the local saturation-wave speed, the phase velocities (CFL condition and TVD
   limiter), dispersion coefficients (Eq. 1.9) and the
   optional IFT-scaled Brooks-Corey capillary pressure (Eq. 1.8).

The work runs as three loops over the cells -- ``_phase_equilibrium`` (steps 1-4, 6 up to the rel-perm inputs),
``_relative_permeabilities`` (the Corey powers) and ``_mobilities`` (steps 5, 7) -- handing intermediate values on
in rows of ``pr``. Every cell sees exactly the arithmetic of a one-cell evaluation (the results are bit-identical);
the split only shortens the per-cell dependency chains so that the CPU overlaps neighbouring cells, and the arrays
are passed once per step rather than once per cell (no per-cell reference counting).

Conjugate phases: aqueous <-> oleic without microemulsion; with microemulsion every excess phase is conjugate to it,
and the microemulsion to its excess phase (in type III to the excess phase present across the larger IFT).
"""

import math

from numba import njit

from . import kernel_inputs as K
from . import state_layout as L
from .physics.adsorption import langmuir_a, langmuir_adsorbed
from .physics.capillary_pressure import LEVERETT_FACTOR_MAX, brooks_corey_pc
from .physics.effective_salinity import phase_behaviour_effective_salinity, polymer_effective_salinity
from .physics.ift import chun_huh_ift, hirasaki_factor
from .physics.microemulsion_viscosity import microemulsion_viscosity
from .physics.permeability_reduction import max_permeability_reduction, permeability_reduction
from .physics.phase_behaviour import NO_MICROEMULSION, TYPE_II_MINUS, TYPE_II_PLUS, flash, solubilization_ratios
from .physics.polymer_viscosity import zero_shear_viscosity
from .physics.relative_permeability import corey, normalized_saturation
from .physics.shear_thinning import equivalent_shear_rate, half_shear_rate, meter_viscosity
from .physics.trapping import endpoint_interpolation, residual_saturation, trapping_number

CP_TO_PA_S = 1.0e-3
MN_M_TO_N_M = 1.0e-3


@njit(cache=True, error_model="numpy")
def adsorbed_amount(total, old, e, a, b, rate, dt_s):
    """Adsorbed amount per pore volume after a step (Eqs. 2.15-2.16).

    ``total`` = fluid + adsorbed per pore volume with storage ``e c + C^``, where ``e`` is the accessible fraction
    (EPHI x carrier saturation) and ``C^ = a c / (1 + b c)``; dividing by ``e`` gives the form of
    ``langmuir_adsorbed`` with ``a/e``. Irreversible in concentration: never below ``old``. With ``rate > 0`` (1/s)
    the adsorbed amount relaxes toward the equilibrium value as ``1 - exp(-rate dt)``.
    """
    if total <= 0.0 or a <= 0.0 or e <= 0.0:
        return old
    eq = e * langmuir_adsorbed(total / e, a / e, b)
    if eq <= old:
        return old
    if rate > 0.0:
        return old + (eq - old) * (-math.expm1(-rate * dt_s))
    return eq


@njit(cache=True, error_model="numpy")
def partly_reversible_adsorbed(total, old, old_irr, e, a, b, frac, rate, dt_s):
    """Adsorbed amount and its irreversible part per pore volume after a step, when a fraction ``frac`` in (0, 1] of
    the Langmuir adsorption (Eqs. 2.15-2.16) is reversible (UTCHEM's adsorption is irreversible in concentration,
    ``frac = 0``: ``adsorbed_amount``; ECLIPSE's PLYROCK adsorption index 1 is ``frac = 1``).

    With the isotherm ``C^(c) = a c / (1 + b c)`` the reversible part is ``frac C^(c)`` at the current fluid
    concentration ``c`` and the irreversible part ``I`` the running maximum of ``(1 - frac) C^(c)``; the total
    ``total = e c + I + frac C^(c)`` is conserved. While the concentration rises above its history (``(1 - frac)
    C^ >= I`` at the full-isotherm equilibrium) the split is that of ``adsorbed_amount``; otherwise ``I`` is held
    and ``c`` solves the Langmuir balance of ``total - I`` with capacity ``frac a``. With ``rate > 0`` (1/s) both the
    adsorbed amount and its irreversible part relax toward these values as ``1 - exp(-rate dt)``, so adsorbed
    polymer also desorbs kinetically. Returns ``(adsorbed, irreversible part)``.
    """
    if total <= 0.0 or a <= 0.0 or e <= 0.0:
        return old, old_irr
    eq = e * langmuir_adsorbed(total / e, a / e, b)
    if (1.0 - frac) * eq >= old_irr:
        irr = (1.0 - frac) * eq
    else:
        irr = old_irr
        eq = irr + e * langmuir_adsorbed(max(total - irr, 0.0) / e, frac * a / e, b)
    if rate > 0.0:
        relax = -math.expm1(-rate * dt_s)
        return old + (eq - old) * relax, old_irr + (irr - old_irr) * relax
    return eq, irr


@njit(cache=True, error_model="numpy")
def _scaled_rk(rkmax, brk, cp, strength):
    """R_k of Eq. 2.7 scaled by the ``permeability_reduction`` effect strength: ``1 + s (R_k - 1)``."""
    return 1.0 + strength * (permeability_reduction(rkmax, brk, cp) - 1.0)


@njit(cache=True, error_model="numpy")
def _pair_ift(l, m, sig_ow, sig13, sig23):
    """IFT (mN/m) between phases ``l`` and ``m`` (0-based: 0 aqueous, 1 oleic, 2 microemulsion)."""
    if l + m == 1:
        return sig_ow
    if l + m == 2:
        return sig13
    return sig23


@njit(cache=True, error_model="numpy")
def _endpoints(l, cj, src, prm, cdc):
    """End point ``k_rl^0`` and Corey exponent ``n_l`` of phase ``l`` (0-based), interpolated by the residual ``src``
    of its conjugate phase ``cj`` when capillary desaturation is on (Eq. 2.13)."""
    if not cdc:
        return prm[K.KR_LOW + l], prm[K.N_LOW + l]
    kr0 = endpoint_interpolation(prm[K.KR_LOW + l], prm[K.KR_HIGH + l], src, prm[K.SR_LOW + cj], prm[K.SR_HIGH + cj])
    nexp = endpoint_interpolation(prm[K.N_LOW + l], prm[K.N_HIGH + l], src, prm[K.SR_LOW + cj], prm[K.SR_HIGH + cj])
    return kr0, nexp


@njit(cache=True, error_model="numpy")
def _phase_equilibrium(st, pr, prm, n, dt_s):
    """Pass 1 (steps 1-4 and 6 up to the rel-perm inputs): salinities, adsorption, flash, polymer carrier, R_k, IFTs,
    trapping numbers, residuals (Eq. 2.12), end points and exponents (Eq. 2.13) and normalized saturations.

    Fills the saturation/composition/polymer/IFT rows of ``pr`` and the rel-perm inputs ``KR`` (end points),
    ``NEXP``, ``SBAR`` (0 for an absent phase), ``WINDOW``. Returns ``(code, cell)``."""
    e3 = prm[K.EPHI3]
    cdc = prm[K.CDC] > 0.0
    sig_ow = prm[K.SIGOW]
    for i in range(n):
        m1 = max(st[L.M1, i], 0.0)
        m2 = max(st[L.M2, i], 0.0)
        if m1 > 0.0:
            c5 = max(st[L.M5, i], 0.0) / m1
            c6 = max(st[L.M6, i], 0.0) / m1
        else:
            c5 = 0.0
            c6 = 0.0
        cse = phase_behaviour_effective_salinity(c5, prm[K.BETA6], prm[K.F6S])

        # surfactant adsorption (total surfactant is known before the flash)
        t3 = st[L.M3, i]
        a3 = langmuir_a(prm[K.AD31], prm[K.AD32], cse, 0.0, 1.0)
        st[L.A3, i] = adsorbed_amount(t3, st[L.A3, i], e3, a3, prm[K.B3D], prm[K.KADS], dt_s)
        c3 = max(t3 - st[L.A3, i], 0.0) / e3

        total = m1 + m2 + c3
        if not total > 0.0:
            return L.ERR_NONFINITE, i
        ptype, s1, s2, s3, c11, c21, c31, c12, c22, c32, c13, c23, c33 = flash(
            m1 / total, m2 / total, c3 / total, cse, prm[K.CSEL], prm[K.CSEU],
            prm[K.HB0], prm[K.HB1], prm[K.HB2], prm[K.EPSME],
        )

        # polymer carrier: the phase (aqueous or microemulsion) holding most of the water
        w1 = s1 * c11
        w3 = s3 * c13
        if w1 <= 0.0 and w3 <= 0.0:
            pcx = 0
            s_c = 0.0
            c1c = 1.0
        elif w1 >= w3:
            pcx = 1
            s_c = s1
            c1c = c11
        else:
            pcx = 3
            s_c = s3
            c1c = c13
        csep = polymer_effective_salinity(c5 * c1c, c6 * c1c, c1c, prm[K.BETAP])
        cp = 0.0
        t4 = st[L.M4, i]
        if s_c > 0.0 and t4 > 0.0:
            e4 = prm[K.EPHI4] * s_c
            a4 = langmuir_a(prm[K.AD41], prm[K.AD42], csep, 0.0, 1.0)
            if prm[K.REV4] > 0.0:
                st[L.A4, i], st[L.A4I, i] = partly_reversible_adsorbed(t4, st[L.A4, i], st[L.A4I, i], e4, a4,
                                                                       prm[K.B4D], prm[K.REV4], prm[K.KADS], dt_s)
            else:
                st[L.A4, i] = adsorbed_amount(t4, st[L.A4, i], e4, a4, prm[K.B4D], prm[K.KADS], dt_s)
            cp = max(t4 - st[L.A4, i], 0.0) / e4
            if prm[K.S_RK] > 0.0 and cp > st[L.CPMAX, i]:
                st[L.CPMAX, i] = cp
                # R_k is non-decreasing in R_k,max <= RKCAP (also in floating point): Eq. 2.8 is only evaluated
                # when R_k at the cap would raise the stored value (not in the far dispersive tail of a slug)
                if _scaled_rk(prm[K.RKCAP], prm[K.BRK], cp, prm[K.S_RK]) > st[L.RK, i]:
                    rkmax = max_permeability_reduction(prm[K.CRK], prm[K.AP1], max(csep, prm[K.CSE1]),
                                                       prm[K.SSLOPE], prm[K.PERM_D], prm[K.PHI], prm[K.RKCAP])
                    rk = _scaled_rk(rkmax, prm[K.BRK], cp, prm[K.S_RK])
                    if rk > st[L.RK, i]:
                        st[L.RK, i] = rk

        # interfacial tensions (mN/m)
        sig13 = sig_ow
        sig23 = sig_ow
        if ptype != NO_MICROEMULSION and s3 > 0.0:
            r13, r23 = solubilization_ratios(c13, c23, c33)
            if ptype != TYPE_II_MINUS:
                sig13 = chun_huh_ift(r13, hirasaki_factor(1.0, 0.0, 0.0, c13, c23, c33), sig_ow, prm[K.CHUH],
                                     prm[K.AHUH])
            if ptype != TYPE_II_PLUS:
                sig23 = chun_huh_ift(r23, hirasaki_factor(0.0, 1.0, 0.0, c13, c23, c33), sig_ow, prm[K.CHUH],
                                     prm[K.AHUH])
        # conjugate phase of each phase (0-based)
        if ptype == NO_MICROEMULSION:
            cj0, cj1, cj2 = 1, 0, 1
        elif ptype == TYPE_II_PLUS:
            cj0, cj1, cj2 = 2, 2, 0
        elif ptype == TYPE_II_MINUS:
            cj0, cj1, cj2 = 2, 2, 1
        else:
            cj0, cj1, cj2 = 2, 2, (1 if (s2 > 0.0 and (sig23 >= sig13 or s1 <= 0.0)) else 0)

        # residual saturations (Eq. 2.12, min(S_l, .)) from the trapping number with k|grad p| of the previous step
        gradk = st[L.GRADK, i]
        sr0 = prm[K.SR_LOW]
        sr1 = prm[K.SR_LOW + 1]
        sr2 = prm[K.SR_LOW + 2]
        if cdc:
            if s1 > 0.0:
                sr0 = residual_saturation(sr0, prm[K.SR_HIGH], prm[K.T1], trapping_number(
                    gradk, _pair_ift(0, cj0, sig_ow, sig13, sig23) * MN_M_TO_N_M), 1.0)
            if s2 > 0.0:
                sr1 = residual_saturation(sr1, prm[K.SR_HIGH + 1], prm[K.T1 + 1], trapping_number(
                    gradk, _pair_ift(1, cj1, sig_ow, sig13, sig23) * MN_M_TO_N_M), 1.0)
            if s3 > 0.0:
                sr2 = residual_saturation(sr2, prm[K.SR_HIGH + 2], prm[K.T1 + 2], trapping_number(
                    gradk, _pair_ift(2, cj2, sig_ow, sig13, sig23) * MN_M_TO_N_M), 1.0)
        sr0 = min(sr0, s1)
        sr1 = min(sr1, s2)
        sr2 = min(sr2, s3)

        # rel-perm inputs of the present phases: end points and exponents (Eq. 2.13), normalized saturations
        # (Eq. 1.7; 0 for an absent phase)
        for l in range(3):
            s_l = s1 if l == 0 else (s2 if l == 1 else s3)
            kr0 = 0.0
            nexp = 0.0
            sbar = 0.0
            if s_l > 0.0:
                cj = cj0 if l == 0 else (cj1 if l == 1 else cj2)
                kr0, nexp = _endpoints(l, cj, sr0 if cj == 0 else (sr1 if cj == 1 else sr2), prm, cdc)
                sbar = normalized_saturation(s_l, sr0, sr1, sr2, sr0 if l == 0 else (sr1 if l == 1 else sr2))
            pr[L.KR + l, i] = kr0
            pr[L.NEXP + l, i] = nexp
            pr[L.SBAR + l, i] = sbar
        pr[L.WINDOW, i] = 1.0 - sr0 - sr1 - sr2

        pr[L.S1, i] = s1
        pr[L.S1 + 1, i] = s2
        pr[L.S1 + 2, i] = s3
        pr[L.C1P, i] = c11
        pr[L.C1P + 1, i] = c12
        pr[L.C1P + 2, i] = c13
        pr[L.C2P, i] = c21
        pr[L.C2P + 1, i] = c22
        pr[L.C2P + 2, i] = c23
        pr[L.C3P, i] = c31
        pr[L.C3P + 1, i] = c32
        pr[L.C3P + 2, i] = c33
        pr[L.CP, i] = cp
        pr[L.CSEP, i] = csep
        pr[L.PCX, i] = pcx
        pr[L.C5, i] = c5
        pr[L.C6, i] = c6
        pr[L.SPC, i] = s_c
        pr[L.PTYPE, i] = ptype
        # IFT of the carrier (wetting) phase against the oleic phase, for the capillary pressure
        pr[L.SIGW, i] = sig23 if pcx == 3 else sig_ow
        # controlling IFT: the largest over the ME/excess-phase interfaces present (the two cross at optimal
        # salinity); oil-water without ME, 0 for a single (miscible) ME phase
        ift = sig_ow
        if ptype != NO_MICROEMULSION and s3 > 0.0:
            ift = 0.0
            if s2 > 0.0:
                ift = sig23
            if s1 > 0.0 and sig13 > ift:
                ift = sig13
        pr[L.IFT, i] = ift
    return L.OK, -1


@njit(cache=True, error_model="numpy")
def _relative_permeabilities(pr, n):
    """Pass 2: Corey ``k_rl = k_rl^0 S_bar^n_l`` (Eq. 2.14) of every present phase and ``dk_rl/dS_l``, from the
    inputs of pass 1; ``KR`` is overwritten with ``k_rl``."""
    for i in range(n):
        window = pr[L.WINDOW, i]
        for l in range(3):
            kr = 0.0
            dkr = 0.0
            if pr[L.S1 + l, i] > 0.0:
                sbar = pr[L.SBAR + l, i]
                nexp = pr[L.NEXP + l, i]
                kr = corey(pr[L.KR + l, i], sbar, nexp)
                if 0.0 < sbar < 1.0 and window > 0.0:
                    dkr = nexp * kr / (sbar * window)
            pr[L.KR + l, i] = kr
            pr[L.DKR + l, i] = dkr


@njit(cache=True, error_model="numpy")
def species_dispersion(pr, i, k0, k1, k2):
    """Dispersion coefficients of the carried species of cell ``i`` from the phase coefficients ``k_l``
    (Eq. 1.9 per phase, ``phi S_l K_l`` in PV units), summed over the phases that carry each species: water and
    salts ``(KW)``, surfactant per overall fluid surfactant ``(KS)`` and polymer in its carrier phase ``(KP)``.
    Reads the saturations, phase compositions and carrier index of ``pr``; also used by the 2-D model with
    directional ``k_l``."""
    c11 = pr[L.C1P, i]
    c13 = pr[L.C1P + 2, i]
    c22 = pr[L.C2P + 1, i]
    c31 = pr[L.C3P, i]
    c32 = pr[L.C3P + 1, i]
    c33 = pr[L.C3P + 2, i]
    sat0 = pr[L.S1, i]
    sat2 = pr[L.S1 + 2, i]
    pcx = int(pr[L.PCX, i])
    kw = k0 * c11 + k1 * (1.0 - c22 - c32) + k2 * c13
    surf = sat0 * c31 + pr[L.S1 + 1, i] * c32 + sat2 * c33
    if surf > 0.0:
        ks = (k0 * c31 + k1 * c32 + k2 * c33) / surf
    elif pcx == 1:
        ks = k0 / sat0
    elif pcx == 3:
        ks = k2 / sat2
    else:
        ks = 0.0
    kp = k0 if pcx == 1 else (k2 if pcx == 3 else 0.0)
    return kw, ks, kp


@njit(cache=True, error_model="numpy")
def release_terms(sat0, sat1, sat2, dl0, dl1, dl2, lam_t, f0, f1, f2, wave_a, wave_o, wave_m):
    """The release phase of a cell (``transport.implicit_release_fluxes``), its term of the wave-speed bound and the
    bound's derivative terms without its column: ``(l, wave_l, speed_x)``.

    ``l`` is the present phase (``sat_l > 0``) with the largest mobility derivative ``dl_l = dlambda_l/dS_l``; its
    column of the fractional-flow Jacobian, ``df_k/dS_l = (delta_kl - f_k) dl_l / lam_t``, dominates the bound
    whose phase terms ``wave_k`` are the row sums of ``|df_k/dS_j|``. With two phases the other phase's term is the
    same derivative (``df_k/dS_k = df_l/dS_l`` on ``S_k + S_l = 1``), which the release takes: ``speed_x = 0``;
    with three, ``speed_x`` is the largest row sum less its entry in column ``l``."""
    rel = 0
    dl_rel = dl0 if sat0 > 0.0 else -1.0
    if sat1 > 0.0 and dl1 > dl_rel:
        rel = 1
        dl_rel = dl1
    if sat2 > 0.0 and dl2 > dl_rel:
        rel = 2
        dl_rel = dl2
    wave_r = wave_a if rel == 0 else (wave_o if rel == 1 else wave_m)
    speed_x = 0.0
    if sat0 > 0.0 and sat1 > 0.0 and sat2 > 0.0:
        col = dl_rel / lam_t
        speed_x = max(wave_a - ((1.0 - f0) if rel == 0 else f0) * col,
                      wave_o - ((1.0 - f1) if rel == 1 else f1) * col,
                      wave_m - ((1.0 - f2) if rel == 2 else f2) * col, 0.0)
    return rel, wave_r, speed_x


@njit(cache=True, error_model="numpy")
def _mobilities(st, pr, prm, n):
    """Pass 3 (steps 5 and 7): polymer and phase viscosities, mobilities, fractional flows, the wave-speed bound,
    phase velocities, dispersion coefficients and the capillary pressure; updates the lagged FPC and GRADK.
    Returns ``(code, cell)``."""
    mu_w = prm[K.VIS1]
    mu_o = prm[K.VIS2]
    mu_o_pa_s = mu_o * CP_TO_PA_S
    e_min = min(prm[K.EPHI3], prm[K.EPHI4])
    dm = prm[K.DMOL] * prm[K.PHI] / (prm[K.UT] * prm[K.LENGTH])
    for i in range(n):
        sat0 = pr[L.S1, i]
        sat1 = pr[L.S1 + 1, i]
        sat2 = pr[L.S1 + 2, i]
        c11 = pr[L.C1P, i]
        c13 = pr[L.C1P + 2, i]
        c21 = pr[L.C2P, i]
        c23 = pr[L.C2P + 2, i]
        c31 = pr[L.C3P, i]
        c33 = pr[L.C3P + 2, i]
        kr_a = pr[L.KR, i]
        kr_o = pr[L.KR + 1, i]
        kr_m = pr[L.KR + 2, i]
        pcx = int(pr[L.PCX, i])
        cp = pr[L.CP, i]

        # viscosities (cP): the polymer solution replaces water in the carrier phase
        mu_solvent = mu_w
        if cp > 0.0:
            csep = pr[L.CSEP, i]
            mu0 = zero_shear_viscosity(mu_w, cp, csep, prm[K.AP1], prm[K.AP2], prm[K.AP3], prm[K.SSLOPE], prm[K.CSE1])
            mu_solvent = mu0
            if prm[K.S_SHEAR] > 0.0:
                if prm[K.IGAMHF] > 0.0:
                    ghalf = half_shear_rate(max(csep, prm[K.CSE1]), cp, prm[K.A0], prm[K.A1], prm[K.A2])
                else:
                    ghalf = prm[K.GAMHF]
                gamma = equivalent_shear_rate(st[L.FPC, i] * prm[K.UT], prm[K.PERM_M2], kr_a if pcx == 1 else kr_m,
                                              prm[K.PHI], pr[L.SPC, i], prm[K.GAMMAC])
                mu_m = meter_viscosity(mu_w, mu0, gamma, ghalf, prm[K.POWN])
                mu_solvent = mu0 - prm[K.S_SHEAR] * (mu0 - mu_m)
        rk = st[L.RK, i]
        mu_a = mu_solvent * rk if pcx == 1 else mu_w
        if sat0 > 0.0 and c31 > 0.0:
            mu_a = microemulsion_viscosity(c11, c21, c31, mu_solvent if pcx == 1 else mu_w, mu_o, prm[K.AV1],
                                           prm[K.AV2], prm[K.AV3], prm[K.AV4], prm[K.AV5]) * (rk if pcx == 1 else 1.0)
        mu_m3 = 1.0
        if sat2 > 0.0:
            mu_m3 = microemulsion_viscosity(c13, c23, c33, mu_solvent if pcx == 3 else mu_w, mu_o, prm[K.AV1],
                                            prm[K.AV2], prm[K.AV3], prm[K.AV4], prm[K.AV5]) * (rk if pcx == 3 else 1.0)

        # phase mobilities (1/(Pa s)); R_k acts as a viscosity multiplier on the carrier phase (Eq. 2.6)
        lam0 = kr_a / (mu_a * CP_TO_PA_S)
        lam1 = kr_o / mu_o_pa_s
        lam2 = kr_m / (mu_m3 * CP_TO_PA_S)
        dl0 = pr[L.DKR, i] / (mu_a * CP_TO_PA_S)
        dl1 = pr[L.DKR + 1, i] / mu_o_pa_s
        dl2 = pr[L.DKR + 2, i] / (mu_m3 * CP_TO_PA_S)
        lam_t = lam0 + lam1 + lam2
        if not lam_t > 0.0:
            return L.ERR_IMMOBILE, i

        f0 = lam0 / lam_t
        f1 = lam1 / lam_t
        f2 = lam2 / lam_t
        st[L.GRADK, i] = prm[K.UT] / lam_t
        st[L.FPC, i] = f0 if pcx == 1 else (f2 if pcx == 3 else 0.0)

        # wave-speed bound (PV units): exact df/dS for two phases, an upper bound for three
        dsum = dl0 + dl1 + dl2
        inv2 = 1.0 / (lam_t * lam_t)
        wave_a = (dl0 * (lam_t - lam0) + lam0 * (dsum - dl0)) * inv2
        wave_o = (dl1 * (lam_t - lam1) + lam1 * (dsum - dl1)) * inv2
        wave_m = (dl2 * (lam_t - lam2) + lam2 * (dsum - dl2)) * inv2
        speed = max(wave_a, wave_o, wave_m)
        pr[L.WAVE, i] = speed
        v0 = f0 / sat0 if sat0 > 0.0 else 0.0
        v1 = f1 / sat1 if sat1 > 0.0 else 0.0
        v2 = f2 / sat2 if sat2 > 0.0 else 0.0
        pr[L.V1, i] = v0
        pr[L.V1 + 1, i] = v1
        pr[L.V1 + 2, i] = v2
        v_bound = max(max(v0, v2) / e_min, v1)
        speed = max(speed, v_bound)
        # the release phase and its term (``transport.implicit_release_fluxes``), and the bound without its column
        rel, wave_r, speed_x = release_terms(sat0, sat1, sat2, dl0, dl1, dl2, lam_t, f0, f1, f2, wave_a, wave_o, wave_m)
        pr[L.REL, i] = rel
        pr[L.WAVE_R, i] = wave_r
        pr[L.SPEED_X, i] = max(speed_x, v_bound)

        # dispersion coefficients (PV units): phi S_l K_l / (u L) = alpha_l f_l / L + phi S_l D / (u L)
        k0 = prm[K.ALPHA_D] * f0 + dm * sat0
        k1 = prm[K.ALPHA_D + 1] * f1 + dm * sat1
        k2 = prm[K.ALPHA_D + 2] * f2 + dm * sat2
        pr[L.KW, i], pr[L.KS, i], pr[L.KP, i] = species_dispersion(pr, i, k0, k1, k2)

        # capillary pressure between the carrier (wetting) phase and the oleic phase (Eq. 1.8, IFT-scaled)
        pr[L.PCAP, i] = 0.0
        pr[L.LWO, i] = 0.0
        pr[L.DCAP, i] = 0.0
        pr[L.DPCDS, i] = 0.0
        if prm[K.PC0] > 0.0 and pcx > 0:
            sbar_w = pr[L.SBAR + pcx - 1, i]
            window = pr[L.WINDOW, i]
            pc = brooks_corey_pc(prm[K.PC0], sbar_w, prm[K.EPC0], pr[L.SIGW, i], prm[K.SIGOW])
            pr[L.PCAP, i] = pc
            lw = lam0 if pcx == 1 else lam2
            lo = lam1
            if lw + lo > 0.0:
                pr[L.LWO, i] = lw * lo / (lw + lo)
            if sbar_w > 0.0 and window > 0.0 and sbar_w ** (-1.0 / prm[K.EPC0]) < LEVERETT_FACTOR_MAX:
                dpc = pc / (prm[K.EPC0] * sbar_w * window)
                pr[L.DPCDS, i] = dpc
                pr[L.DCAP, i] = prm[K.PERM_M2] * pr[L.LWO, i] * dpc / (prm[K.UT] * prm[K.LENGTH])

        pr[L.F1, i] = f0
        pr[L.F1 + 1, i] = f1
        pr[L.F1 + 2, i] = f2
        pr[L.LAMT, i] = lam_t
        pr[L.SPEED, i] = speed
    return L.OK, -1


@njit(cache=True, error_model="numpy")
def cell_properties(st, pr, prm, n, dt_s):
    """Fill ``pr[:, i]`` from ``st[:, i]`` for every cell ``i < n`` (and update the irreversible A3, A4, RK and the
    lagged FPC, GRADK).

    Three passes over the cells (module docstring). Returns ``(code, cell)``: ``(OK, -1)``, or an error code of
    ``state_layout`` (``ERR_NONFINITE`` for an empty cell, ``ERR_IMMOBILE`` when no phase can flow) and the failing
    cell."""
    code, cell = _phase_equilibrium(st, pr, prm, n, dt_s)
    if code != L.OK:
        return code, cell
    _relative_permeabilities(pr, n)
    return _mobilities(st, pr, prm, n)
