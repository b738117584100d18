"""Dense output of the time loops (1-D ``kernel`` and 2-D ``two_d.kernel2d``): the effluent series at output times
that fall inside a time step, so that the output grid never steers the step sequence.

Within one explicit step the face fluxes are constant, so the cumulative produced amounts are exactly linear in time
between the step's ends: the cumulative amount at an output time ``tau`` in ``(t_prev, t]`` is the linear
interpolation of the cumulative amounts at the two ends, and the interval averages of the effluent (oil cut,
effluent concentrations) follow exactly from differences of cumulative amounts. The pressure drop is a point value
of the state; it is interpolated linearly between the values at the step's ends (an ``O(dt^2)`` interpolation error
where it is smooth, far below the scheme's own error; the step never exceeds the CFL limit).

The cumulative vector ``cum[N_CUM]`` holds the produced water, oil, surfactant, polymer, anions, divalent cations
(the ``transport`` flux rows) and the produced volume of the polymer-carrying phase (``CARRIER``), in PV units.
"""

from numba import njit

from . import transport as T

# series rows (shared by the 1-D and 2-D kernels)
DP, OIL_CUT, RECOVERY, CP_OUT, CS_OUT, SAL_OUT = range(6)
N_SERIES = 6
CARRIER = 6
N_CUM = 7


@njit(cache=True, error_model="numpy")
def record_outputs(series, out_pv, k_out, t_prev, t, dp_prev, dp_now, cum_prev, cum_now, cum_last, t_last, ooip,
                   salinity_now, delta):
    """Fill ``series[:, k]`` for every output time ``out_pv[k]`` in ``(t_prev, t]`` from ``k = k_out`` on.

    ``cum_prev``/``cum_now`` are the cumulative produced amounts at the step's ends ``t_prev``/``t``; ``cum_last``
    (updated in place) holds them at the previous output time ``t_last``; ``delta[N_CUM]`` is scratch space.
    ``salinity_now`` is the outlet salinity reported for an interval that produced no water. Returns
    ``(k_out, t_last)`` after the records."""
    n_out = out_pv.shape[0]
    while k_out < n_out and out_pv[k_out] <= t:
        tau = out_pv[k_out]
        w = (tau - t_prev) / (t - t_prev) if t > t_prev else 1.0
        for r in range(N_CUM):
            c = cum_prev[r] + w * (cum_now[r] - cum_prev[r])
            delta[r] = c - cum_last[r]
            cum_last[r] = c
        span = tau - t_last
        series[DP, k_out] = dp_prev + w * (dp_now - dp_prev)
        series[RECOVERY, k_out] = cum_last[T.FO] / ooip if ooip > 0.0 else 0.0
        series[OIL_CUT, k_out] = delta[T.FO] / span if span > 0.0 else 0.0
        series[CS_OUT, k_out] = delta[T.FS] / span if span > 0.0 else 0.0
        series[CP_OUT, k_out] = delta[T.FP] / delta[CARRIER] if delta[CARRIER] > 0.0 else 0.0
        series[SAL_OUT, k_out] = delta[T.FA] / delta[T.FW] if delta[T.FW] > 0.0 else salinity_now
        t_last = tau
        k_out += 1
    return k_out, t_last
