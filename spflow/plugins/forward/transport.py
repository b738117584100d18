"""Component transport on the 1-D grid: explicit TVD face fluxes, implicit dispersion and capillary fluxes, pressure.

Units: pore-volume units throughout -- fluxes are fractions of the total Darcy flux ``u`` (which is uniform along the
core: incompressible fluids and rock, constant injection rate), distances are ``x/L`` and time is injected pore
volumes. Face ``j`` lies between cells ``j-1`` and ``j``; face 0 is the injector, face ``n`` the producer.

Advection (``advective_fluxes``): the total velocity is positive, so the upwind cell of face ``j`` is ``j-1``.
``scheme = upwind`` takes the upwind cell's phase fractional flows and phase compositions. ``scheme = tvd`` is
Sweby's flux-limited scheme with the van Leer limiter: face value
``q_face = q_i + (1 - nu_i) D- D+ / (D- + D+)`` if ``D- D+ > 0`` else ``q_i`` (``D- = q_i - q_{i-1}``,
``D+ = q_{i+1} - q_i``; this is ``q_i + psi(r) (1 - nu) D+ / 2`` with ``psi(r) = (r + |r|)/(1 + |r|)``), where
``nu_i`` is the local Courant number of the reconstructed quantity: ``dt/dx`` times the saturation-wave speed for
the phase fractional flows (renormalised to sum to 1, so that the component volume fluxes sum to the total flux
exactly) and times the carrier-phase velocity for the surfactant fraction of each phase, the polymer concentration
of the carrier phase and the salinity per water volume. In smooth regions (``psi = 1``) this is the Lax-Wendroff flux,
second order in space and time; at extrema it falls back to upwind. As ``0 <= psi <= 2`` and ``0 <= psi/r <= 2`` the
scheme is TVD for Courant numbers up to 1/2 whatever ``nu`` in [0, 1] the factor uses, which the time step
guarantees (``cfl <= 0.5``). The first interior face and the producer face are first order.

Implicit release (``implicit_release_fluxes``; the kernel's budgeted mode past its share of the step budget): the
outflow faces of cells whose release-phase Courant number exceeds the limit take the linearised backward-Euler
upwind fraction of that phase, swept from the inlet, so the step need not resolve a fast wave of a phase a hair
above its residual (oil, or the aqueous or microemulsion phase) that carries almost none of it.

Dispersion (``solve_dispersion``; Eq. 1.9 per phase, summed over phases for each carried species): backward
Euler in the species' carrier concentration (a tridiagonal M-matrix, unconditionally stable and positivity
preserving), written back as conservative face fluxes, with no dispersive flux through the injector and producer
faces (Danckwerts conditions).

Capillary fluxes (Eq. 1.8; the carrier phase moves towards higher ``Pc``, pure oil the other way): linearly
implicit, backward Euler in the carrier saturation with the mobilities and chord ``dPc/dS`` lagged at the step start
(``implicit_capillary_fluxes``, operator split after the advection), or explicit (``capillary_fluxes``, the
reference path, stable only for ``dt <= dx^2 / (2 max D_cap)``).
"""

from numba import njit

from . import state_layout as L
from .physics.capillary_pressure import brooks_corey_pc

# flux rows: water, oil, surfactant, polymer, anions, divalent
FW, FO, FS, FP, FA, FD = 0, 1, 2, 3, 4, 5
NFLUX = 6


@njit(cache=True, error_model="numpy")
def van_leer_face(qm, q0, qp, w):
    """Limited face value downstream of ``q0`` from the upstream ``qm`` and downstream ``qp`` neighbours;
    ``w = 1 - nu`` in [0, 1] is the Lax-Wendroff factor."""
    dm = q0 - qm
    dp = qp - q0
    if dm * dp > 0.0:
        return q0 + w * dm * dp / (dm + dp)
    return q0


@njit(cache=True, error_model="numpy")
def _lw_factor(courant, speed):
    """``1 - nu`` clipped to [0, 1]."""
    nu = courant * speed
    return 1.0 - nu if nu < 1.0 else 0.0


@njit(cache=True, error_model="numpy")
def phase_fraction_fluxes(pr, i, f0, f1, f2, out, j):
    """Fluxes of face ``j`` carrying the phase fractional flows ``f0, f1, f2`` with the compositions of cell ``i``;
    returns the fraction of the polymer-carrying phase."""
    fw = 0.0
    fo = 0.0
    fs = 0.0
    for l in range(3):
        f = f0 if l == 0 else (f1 if l == 1 else f2)
        fo += f * pr[L.C2P + l, i]
        fs += f * pr[L.C3P + l, i]
        fw += f * (1.0 - pr[L.C2P + l, i] - pr[L.C3P + l, i])
    pcx = int(pr[L.PCX, i])
    fc = f0 if pcx == 1 else (f2 if pcx == 3 else 0.0)
    out[FW, j] = fw
    out[FO, j] = fo
    out[FS, j] = fs
    out[FP, j] = fc * pr[L.CP, i]
    out[FA, j] = fw * pr[L.C5, i]
    out[FD, j] = fw * pr[L.C6, i]
    return fc


@njit(cache=True, error_model="numpy")
def upwind_cell_fluxes(pr, i, out, j):
    """First-order fluxes of face ``j`` from cell ``i``."""
    phase_fraction_fluxes(pr, i, pr[L.F1, i], pr[L.F1 + 1, i], pr[L.F1 + 2, i], out, j)


@njit(cache=True, error_model="numpy")
def implicit_release_fluxes(pr, n, lam, cfl, out):
    """Replace the outflow face fluxes of every cell whose release-phase Courant number ``lam * WAVE_R`` exceeds
    ``cfl`` with the linearised backward-Euler upwind ones (the stiff release of a phase near its residual,
    docs/forward_model.md). The release phase ``l = REL`` of a cell is the one with the largest mobility derivative
    (``cell_properties``): the oleic phase near its residual oil saturation, or the aqueous or microemulsion phase
    near theirs.

    The total velocity is positive, so implicit upwind transport solves cell by cell from the inlet. Linearising the
    phase-``l`` fractional flow of cell ``i`` about the step start, ``f(S) ~ f^n + c (S - S^n)`` with
    ``c = df_l/dS_l``, the backward-Euler update ``S - S^n = -lam (f(S) - F_in)`` gives the outflow

        F = (f^n + lam c F_in) / (1 + lam c),

    a weighted mean of the cell's explicit phase-``l`` fraction and the phase-``l`` fraction entering it
    (``F_in``: the released fraction of a released upstream cell, else the upstream cell's own, its face then first
    order; at the injector, which brings no oil, 0 for the oleic phase and the cell's share of the non-oleic flow
    ``f_l / (1 - f_o)`` for the other two). The other phases keep their ratios, scaled to a total of ``1 - F`` (the
    linearised change of the other fractional flows along ``S_l``: ``df_k/dS_l = -f_k / (1 - f_l) df_l/dS_l``);
    the components go with the cell's phase compositions, so the update stays conservative. Returns ``(cells
    released, of which in the aqueous or microemulsion phase, carrier fraction at the producer face or -1 if the
    last cell was not released)``."""
    count = 0
    count_non_oleic = 0
    released_up = False  # whether the upstream cell was released (its face fractions then ``f_up``)
    f_up0 = 0.0
    f_up1 = 0.0
    f_up2 = 0.0
    fc_out = -1.0
    for i in range(n):
        c = pr[L.WAVE_R, i]
        l = int(pr[L.REL, i])
        f_l = pr[L.F1 + l, i]
        if not (lam * c > cfl and f_l < 1.0):
            released_up = False
            continue
        count += 1
        if l != 1:
            count_non_oleic += 1
        if i == 0:
            f_o = pr[L.F1 + 1, i]
            f_in = 0.0 if l == 1 or f_o >= 1.0 else f_l / (1.0 - f_o)
        elif released_up:
            f_in = f_up0 if l == 0 else (f_up1 if l == 1 else f_up2)
        else:
            upwind_cell_fluxes(pr, i - 1, out, i)
            f_in = pr[L.F1 + l, i - 1]
        f_new = (f_l + lam * c * f_in) / (1.0 + lam * c)
        scale = (1.0 - f_new) / (1.0 - f_l)
        f_up0 = f_new if l == 0 else pr[L.F1, i] * scale
        f_up1 = f_new if l == 1 else pr[L.F1 + 1, i] * scale
        f_up2 = f_new if l == 2 else pr[L.F1 + 2, i] * scale
        fc = phase_fraction_fluxes(pr, i, f_up0, f_up1, f_up2, out, i + 1)
        if i == n - 1:
            fc_out = fc
        released_up = True
    return count, count_non_oleic, fc_out


@njit(cache=True, error_model="numpy")
def advective_fluxes(pr, n, tvd, courant, e3, e4, inj3, inj4, inj5, inj6, out):
    """Fill ``out[NFLUX, n + 1]`` with the advective component fluxes (PV units) of every face.

    ``courant = dt/dx``; ``e3``, ``e4`` are the accessible pore fractions of surfactant and polymer (their
    velocities are the carrier velocities divided by them)."""
    out[FW, 0] = 1.0 - inj3
    out[FO, 0] = 0.0
    out[FS, 0] = inj3
    out[FP, 0] = inj4
    out[FA, 0] = (1.0 - inj3) * inj5
    out[FD, 0] = (1.0 - inj3) * inj6
    for j in range(1, n + 1):
        i = j - 1
        if not tvd or i == 0 or j == n:
            upwind_cell_fluxes(pr, i, out, j)
            continue
        w = _lw_factor(courant, pr[L.WAVE, i])
        f0 = van_leer_face(pr[L.F1, i - 1], pr[L.F1, i], pr[L.F1, i + 1], w)
        f1 = van_leer_face(pr[L.F1 + 1, i - 1], pr[L.F1 + 1, i], pr[L.F1 + 1, i + 1], w)
        f2 = van_leer_face(pr[L.F1 + 2, i - 1], pr[L.F1 + 2, i], pr[L.F1 + 2, i + 1], w)
        tot = f0 + f1 + f2
        if not tot > 1.0e-12:
            upwind_cell_fluxes(pr, i, out, j)
            continue
        fw = 0.0
        fo = 0.0
        fs = 0.0
        for l in range(3):
            f = (f0 if l == 0 else (f1 if l == 1 else f2)) / tot
            if f <= 0.0:
                continue
            c2 = pr[L.C2P + l, i]
            c3 = pr[L.C3P + l, i]
            if pr[L.S1 + l, i - 1] > 0.0 and pr[L.S1 + l, i + 1] > 0.0:
                c3 = van_leer_face(pr[L.C3P + l, i - 1], c3, pr[L.C3P + l, i + 1],
                                   _lw_factor(courant, pr[L.V1 + l, i] / e3))
            fo += f * c2
            fs += f * c3
            fw += f * (1.0 - c2 - c3)
        pcx = int(pr[L.PCX, i])
        fc = 0.0
        cp = pr[L.CP, i]
        v_water = 0.0
        if pcx > 0:
            fc = (f0 if pcx == 1 else f2) / tot
            v_water = pr[L.V1 + pcx - 1, i]
            if pr[L.PCX, i - 1] > 0.0 and pr[L.PCX, i + 1] > 0.0:
                cp = van_leer_face(pr[L.CP, i - 1], cp, pr[L.CP, i + 1], _lw_factor(courant, v_water / e4))
        ws = _lw_factor(courant, v_water)
        out[FW, j] = fw
        out[FO, j] = fo
        out[FS, j] = fs
        out[FP, j] = fc * cp
        out[FA, j] = fw * van_leer_face(pr[L.C5, i - 1], pr[L.C5, i], pr[L.C5, i + 1], ws)
        out[FD, j] = fw * van_leer_face(pr[L.C6, i - 1], pr[L.C6, i], pr[L.C6, i + 1], ws)


@njit(cache=True, error_model="numpy")
def add_capillary_face(pr, j, g, out):
    """Add the carrier-phase capillary flux ``g`` (PV units, positive towards cell ``j``) of interior face ``j`` to
    ``out``: the carrier phase carries the composition of the cell it leaves (water, oil, surfactant, polymer and the
    salinity of its water), the oleic phase moves ``-g`` of pure oil the other way, so the face's volume fluxes sum
    to zero."""
    if g == 0.0:
        return
    up = j - 1 if g > 0.0 else j  # the carrier phase leaves this cell; pure oil flows the other way
    l = 0 if int(pr[L.PCX, up]) == 1 else 2
    c2 = pr[L.C2P + l, up]
    c3 = pr[L.C3P + l, up]
    water = g * (1.0 - c2 - c3)
    out[FW, j] += water
    out[FO, j] += g * c2 - g
    out[FS, j] += g * c3
    out[FP, j] += g * pr[L.CP, up]
    out[FA, j] += water * pr[L.C5, up]
    out[FD, j] += water * pr[L.C6, up]


@njit(cache=True, error_model="numpy")
def capillary_face_mobility(pr, j):
    """Harmonic mean of the cells' ``lw lo / (lw + lo)`` at interior face ``j`` (0 if either cell has none)."""
    a = pr[L.LWO, j - 1]
    b = pr[L.LWO, j]
    if a <= 0.0 or b <= 0.0:
        return 0.0
    return 2.0 * a * b / (a + b)


@njit(cache=True, error_model="numpy")
def capillary_fluxes(pr, n, dx, prm_k_over_ul, out):
    """Add the explicit capillary fluxes (Eq. 1.8; ``Pc = p_oleic - p_carrier``) to the interior faces of ``out``.

    The carrier (wetting) phase moves with ``G = k (lw lo/(lw + lo))_face (Pc_{i+1} - Pc_i) / (u L dx)`` (PV units,
    harmonic face mobility), the oleic phase with ``-G`` (``add_capillary_face``). Stable for
    ``dt <= dx^2 / (2 max D_cap)``; the kernel's reference path (``capillary="explicit"``)."""
    for j in range(1, n):
        g = prm_k_over_ul * capillary_face_mobility(pr, j) * (pr[L.PCAP, j] - pr[L.PCAP, j - 1]) / dx
        add_capillary_face(pr, j, g, out)


@njit(cache=True, error_model="numpy")
def _carrier_pc(pr, i, s, pc0, lambda_b, sigma_ref):
    """Capillary pressure of cell ``i``'s curve (its residuals, window and IFT, Eq. 1.8) at carrier saturation ``s``
    (its own Pc where the saturation window is empty)."""
    window = pr[L.WINDOW, i]
    if not window > 0.0:
        return pr[L.PCAP, i]
    l = int(pr[L.PCX, i]) - 1
    sbar = pr[L.SBAR + l, i] + (s - pr[L.S1 + l, i]) / window
    return brooks_corey_pc(pc0, sbar, lambda_b, pr[L.SIGW, i], sigma_ref)


@njit(cache=True, error_model="numpy")
def implicit_capillary_fluxes(pr, n, dx, lam, prm_k_over_ul, pc0, lambda_b, sigma_ref, ds_adv, work, out):
    """Add the linearly implicit (backward-Euler) capillary fluxes of a step ``lam = dt/dx`` to ``out``.

    Unknown: the carrier saturation ``S_i`` at the end of the step, from ``S_i^a = S_i + ds_adv_i`` after the
    advection. The face flux ``G_j = a_j (Pc_j(S_j) - Pc_{j-1}(S_{j-1}))`` (``a_j = k (lw lo/(lw + lo))_face /
    (u L dx)``, ``Pc_i(.)`` cell ``i``'s Brooks-Corey curve) splits exactly into a saturation part and a part from
    the difference of the two cells' curves (IFT, residuals) at equal saturation:
    ``G_j = -A_j (S_j - S_{j-1}) + R_j`` with the chord diffusivity
    ``A_j = -a_j [Pc_j(S_j) - Pc_j(S_{j-1}) + Pc_{j-1}(S_j) - Pc_{j-1}(S_{j-1})] / (2 (S_j - S_{j-1})) >= 0``
    (``a_j`` times the mean ``|dPc/dS|`` of the cell's tangent ``DPCDS`` where the saturations are equal) and
    ``R_j = a_j [Pc_j(S_j) - Pc_{j-1}(S_j) + Pc_j(S_{j-1}) - Pc_{j-1}(S_{j-1})] / 2``, both at the step start
    (lagged coefficients). The saturation part is implicit, the curve part explicit (0 for uniform rock and IFT):

    ``(1 + lam (A_i + A_{i+1})) S_i - lam A_i S_{i-1} - lam A_{i+1} S_{i+1} = S_i^a - lam (R_{i+1} - R_i)``

    (``A_0 = A_n = R_0 = R_n = 0``: no capillary flux through the end faces). The matrix is an M-matrix with unit
    column sums, so the solve is unconditionally stable and, with ``R = 0``, keeps every ``S_i`` inside the range of
    the ``S^a`` (a discrete maximum principle); the Thomas algorithm needs no pivoting. The fluxes ``G_j`` go to
    ``out`` with upwind compositions (``add_capillary_face``): conservative by construction. ``work[5, n + 1]``
    is scratch."""
    a = work[0]
    r = work[1]
    sa = work[2]
    cw = work[3]
    dw = work[4]
    a[0] = 0.0
    a[n] = 0.0
    r[0] = 0.0
    r[n] = 0.0
    for i in range(n):
        pcx = int(pr[L.PCX, i])
        sa[i] = pr[L.S1 + pcx - 1, i] + ds_adv[i] if pcx > 0 else 0.0
    for j in range(1, n):
        mob = prm_k_over_ul * capillary_face_mobility(pr, j) / dx
        a[j] = 0.0
        r[j] = 0.0
        if mob == 0.0:
            continue
        s_l = pr[L.S1 + int(pr[L.PCX, j - 1]) - 1, j - 1]
        s_r = pr[L.S1 + int(pr[L.PCX, j]) - 1, j]
        p_rr = pr[L.PCAP, j]
        p_ll = pr[L.PCAP, j - 1]
        p_rl = _carrier_pc(pr, j, s_l, pc0, lambda_b, sigma_ref)
        p_lr = _carrier_pc(pr, j - 1, s_r, pc0, lambda_b, sigma_ref)
        ds = s_r - s_l
        if ds != 0.0:
            a[j] = -mob * 0.5 * ((p_rr - p_rl) + (p_lr - p_ll)) / ds
        else:
            a[j] = mob * 0.5 * (pr[L.DPCDS, j - 1] + pr[L.DPCDS, j])
        r[j] = mob * 0.5 * ((p_rr - p_lr) + (p_rl - p_ll))
    # forward sweep (cw: modified super-diagonal, dw: modified right-hand side)
    for i in range(n):
        diag = 1.0 + lam * (a[i] + a[i + 1])
        rhs = sa[i] - lam * (r[i + 1] - r[i])
        upper = -lam * a[i + 1]
        if i > 0:
            lower = -lam * a[i]
            denom = diag - lower * cw[i - 1]
            cw[i] = upper / denom
            dw[i] = (rhs - lower * dw[i - 1]) / denom
        else:
            cw[i] = upper / diag
            dw[i] = rhs / diag
    for i in range(n - 2, -1, -1):
        dw[i] -= cw[i] * dw[i + 1]
    for j in range(1, n):
        g = r[j] - a[j] * (dw[j] - dw[j - 1])
        add_capillary_face(pr, j, g, out)


@njit(cache=True, error_model="numpy")
def solve_dispersion(storage, conc, coef, n, lam, work_c, work_d, out_j):
    """Backward-Euler dispersion of the species ``k`` (rows of the ``[m, n]`` arrays), all solved in one sweep.

    Species ``k`` has concentration ``conc[k]``, storage ``storage[k]`` per cell and cell coefficients ``coef[k]``;
    the face coefficient is the mean of the two cells and ``lam = dt / dx^2``. Solves
    ``storage_i c_i - lam [K+ (c_{i+1} - c_i) - K- (c_i - c_{i-1})] = storage_i conc_i`` (Thomas algorithm) and
    returns the face fluxes ``J_j = -K_j (c_j - c_{j-1}) / dx`` times ``dx`` in ``out_j[k]`` (so that the update is
    ``m_i -= lam (J_{i+1} - J_i)``). The species are independent systems; sweeping them together row by row lets
    their recurrences overlap on the CPU (each system sees exactly the operations of a solve on its own)."""
    m = storage.shape[0]
    # forward sweep: work_c = modified super-diagonal, work_d = modified rhs
    for i in range(n):
        for k in range(m):
            kl = 0.5 * (coef[k, i - 1] + coef[k, i]) * lam if i > 0 else 0.0
            kr = 0.5 * (coef[k, i] + coef[k, i + 1]) * lam if i < n - 1 else 0.0
            diag = storage[k, i] + kl + kr
            rhs = storage[k, i] * conc[k, i]
            if i > 0:
                denom = diag + kl * work_c[k, i - 1]
                if denom > 0.0:
                    work_c[k, i] = -kr / denom
                    work_d[k, i] = (rhs + kl * work_d[k, i - 1]) / denom
                else:
                    work_c[k, i] = 0.0
                    work_d[k, i] = conc[k, i]
            else:
                if diag > 0.0:
                    work_c[k, i] = -kr / diag
                    work_d[k, i] = rhs / diag
                else:
                    work_c[k, i] = 0.0
                    work_d[k, i] = conc[k, i]
    for i in range(n - 2, -1, -1):
        for k in range(m):
            work_d[k, i] -= work_c[k, i] * work_d[k, i + 1]
    for k in range(m):
        out_j[k, 0] = 0.0
        out_j[k, n] = 0.0
        for j in range(1, n):
            out_j[k, j] = -0.5 * (coef[k, j - 1] + coef[k, j]) * (work_d[k, j] - work_d[k, j - 1])


@njit(cache=True, error_model="numpy")
def pressure_profile(pr, n, dx_m, u, k_m2, out):
    """Global pressure (Pa, producer at 0) at the cell centres, and the injector-face value as the return value.

    ``dp/dx = -u / (k lambda_T)`` integrated cell by cell: the IMPES pressure "solve" for a uniform total flux. With
    capillary pressure on, this is Chavent's global pressure, whose gradient is the total velocity's alone; a phase
    pressure differs from it by a function of the local state (for the oleic phase ``int f_c dPc``), so the phase
    pressure drops differ from it only by the difference of that function between the two end cells. The phase
    form is not used: integrated cell by cell it adds ``f_c (Pc_{i+1} - Pc_i)`` at every face, and across the faces
    where the carrier switches between water and microemulsion, where a cell has no oleic phase (Pc undefined) or
    where a connate cell sits at the capped Pc, those jumps are artefacts of the discretisation that made the
    pressure drop jump by percents as a parameter moved by 1e-4 (docs/forward_model.md)."""
    p = 0.5 * u * dx_m / (k_m2 * pr[L.LAMT, n - 1])
    out[n - 1] = p
    for i in range(n - 2, -1, -1):
        p += 0.5 * u * dx_m / k_m2 * (1.0 / pr[L.LAMT, i] + 1.0 / pr[L.LAMT, i + 1])
        out[i] = p
    return p + 0.5 * u * dx_m / (k_m2 * pr[L.LAMT, 0])
