"""The capillary steps of the transport module against an independent solution of the same semi-discrete equation.

Capillary redistribution alone (no advection) on a small grid of uniform rock: water-oil, constant face mobility,
Brooks-Corey ``Pc(S) = pc0 S_bar^(-1/lambda)`` with ``S_bar = (S - S_wr) / (1 - S_wr - S_or)`` (Eq. 1.8, written
out here), carrier saturation ``S_i`` of cell ``i`` and face fluxes ``G_j = a (Pc(S_j) - Pc(S_{j-1})) / dx``, none
through the end faces: ``dS_i/dt = -(G_{i+1} - G_i) / dx``. The reference integrates this ODE system with scipy's
Radau method at tight tolerances; the kernel's backward-Euler (``implicit_capillary_fluxes``) and forward-Euler
(``capillary_fluxes``) steps, with the cell properties refreshed from the state before every step as the kernel
does, must converge to it at first order in the step and conserve the water exactly.
"""

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from spflow.plugins.forward import state_layout as L
from spflow.plugins.forward import transport as T

N = 12
DX = 1.0 / N
SWR, SOR = 0.2, 0.2
WINDOW = 1.0 - SWR - SOR
PC0, LAMBDA = 1.0, 2.0
K_OVER_UL = 0.02  # the capillary diffusivity scale (PV units)
MOBILITY = 1.0  # lw lo / (lw + lo) of every cell
T_END = 0.2
S0 = np.where(np.arange(N) < N // 3, 0.7, 0.3)  # water-wet imbibition from a wet third into the rest


def pc(s):
    return PC0 * ((s - SWR) / WINDOW) ** (-1.0 / LAMBDA)


def dpc_abs(s):
    return PC0 / (LAMBDA * WINDOW) * ((s - SWR) / WINDOW) ** (-1.0 / LAMBDA - 1.0)


def rhs(_t, s):
    g = np.zeros(N + 1)
    g[1:N] = K_OVER_UL * MOBILITY * (pc(s[1:]) - pc(s[:-1])) / DX
    return -(g[1:] - g[:-1]) / DX


def reference():
    sol = solve_ivp(rhs, (0.0, T_END), S0, method="Radau", rtol=1e-11, atol=1e-13)
    assert sol.success
    return sol.y[:, -1]


def properties(s):
    """The property rows the capillary functions read, for cells holding water (the carrier) and oil only."""
    pr = np.zeros((L.NPR, N))
    pr[L.PCX] = 1.0
    pr[L.S1] = s
    pr[L.S1 + 1] = 1.0 - s
    pr[L.SBAR] = (s - SWR) / WINDOW
    pr[L.WINDOW] = WINDOW
    pr[L.SIGW] = 1.0
    pr[L.LWO] = MOBILITY
    pr[L.PCAP] = pc(s)
    pr[L.DPCDS] = dpc_abs(s)
    return pr  # phase compositions 0: the carrier is pure water, its flux the water flux


def integrate(steps, implicit):
    dt = T_END / steps
    lam = dt / DX
    s = S0.copy()
    work = np.zeros((5, N + 1))
    for _ in range(steps):
        pr = properties(s)
        out = np.zeros((T.NFLUX, N + 1))
        if implicit:
            T.implicit_capillary_fluxes(pr, N, DX, lam, K_OVER_UL, PC0, LAMBDA, 1.0, np.zeros(N), work, out)
        else:
            T.capillary_fluxes(pr, N, DX, K_OVER_UL, out)
        np.testing.assert_allclose(out[T.FW] + out[T.FO], 0.0, atol=1e-14)  # counter-current: no net volume
        s = s - lam * (out[T.FW, 1:] - out[T.FW, :-1])
    return s


@pytest.mark.parametrize("implicit", [True, False], ids=["backward_euler", "forward_euler"])
def test_capillary_step_converges_to_the_method_of_lines_solution(implicit):
    ref = reference()
    assert np.ptp(ref) > 0.1  # the profile is still far from uniform: the test sees the transient
    # the explicit step is stable for dt <= dx^2 / (2 D), D = K_OVER_UL * |Pc'| <= 0.245 here: dt <= 0.014
    steps = (200, 400, 800)
    errors = []
    for k in steps:
        s = integrate(k, implicit)
        assert abs(s.sum() - S0.sum()) <= 1e-12  # conservative
        errors.append(np.max(np.abs(s - ref)))
    orders = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert errors[-1] <= 1e-4, errors
    assert np.all((orders > 0.8) & (orders < 1.3)), (errors, orders)


def test_backward_euler_is_stable_beyond_the_explicit_limit():
    """Two steps at 7 x the explicit diffusion limit: the backward-Euler profile stays inside the initial range
    (discrete maximum principle), conserves and is within 0.03 of the reference (first order at a large step);
    forward Euler at the same step leaves the range (the case is beyond its stability limit)."""
    ref = reference()
    d_max = K_OVER_UL * MOBILITY * dpc_abs(S0.min())
    steps = 2
    assert (T_END / steps) / (DX * DX / (2.0 * d_max)) > 5.0
    s = integrate(steps, implicit=True)
    assert np.all(s >= S0.min() - 1e-12) and np.all(s <= S0.max() + 1e-12)
    assert abs(s.sum() - S0.sum()) <= 1e-12
    assert np.max(np.abs(s - ref)) <= 0.03
    with np.errstate(invalid="ignore"):
        explicit = integrate(steps, implicit=False)
    assert not (np.all(explicit >= S0.min()) and np.all(explicit <= S0.max()))
