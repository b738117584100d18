"""Coreflood signatures and their posterior-predictive p-values ("process-relevant" checks in
the sense of Gupta, Wagener & Liu 2008; docs/gap.md, Method: **Where**).

From the series of one experiment on its grid (NaN where not measured):

* ``water_breakthrough`` (PV) — where the oil cut first falls below 0.5 after having been at or above it
  (linear interpolation between grid points);
* ``oil_bank`` (PV) — where the oil cut first rises 0.05 above its value at the start of the first
  surfactant-bearing slug (the oil bank reaching the outlet);
* ``plateau_dp:<slug>`` (Pa) — median pressure drop over the last 30 % of each slug;
* ``rrf`` (-) — residual resistance after polymer: the plateau of the last polymer-free slug after polymer divided
  by the plateau of the first slug (the initial water flood);
* ``incremental_recovery:<slug>`` (-) — recovery at the end of each slug minus at its start.

A signature whose inputs are not measured is NaN. The predictive p-value of a statistic ``T`` is two-sided,
``2 min(P(T_rep <= T_obs), P(T_rep >= T_obs))`` over replicated data ``y_rep = y_fit + J dz + e`` (linearised
parameter uncertainty ``dz ~ N(0, (J_w' J_w)^-1)`` from the calibration fit plus measurement errors ``e`` drawn from
the error model), with the (count + 1) / (N + 1) estimator.
"""

from __future__ import annotations

import numpy as np

from .observed import Experiment

__all__ = ["signatures", "SIGNATURE_UNITS", "predictive_pvalues"]

#: signature prefix -> units
SIGNATURE_UNITS = {"water_breakthrough": "PV", "oil_bank": "PV", "plateau_dp": "Pa", "rrf": "1",
                   "incremental_recovery": "1"}


def _crossing(pv: np.ndarray, y: np.ndarray, level: float, start: int, rising: bool) -> float:
    for i in range(max(start, 1), pv.size):
        a, b = y[i - 1], y[i]
        if not (np.isfinite(a) and np.isfinite(b)):
            continue
        if (a < level <= b) if rising else (a >= level > b):
            return float(pv[i - 1] + (level - a) / (b - a) * (pv[i] - pv[i - 1]))
    return float("nan")


def _plateau(pv, dp, lo, hi) -> float:
    m = (pv >= lo + 0.7 * (hi - lo) - 1e-9) & (pv <= hi + 1e-9) & np.isfinite(dp)
    return float(np.median(dp[m])) if m.any() else float("nan")


def _at(pv, y, x) -> float:
    if x <= 1e-12:
        return 0.0
    m = np.isfinite(y)
    return float(np.interp(x, pv[m], y[m])) if m.sum() >= 2 and pv[m][0] <= x + 1e-9 else float("nan")


def signatures(exp: Experiment, series: dict[str, np.ndarray]) -> dict[str, float]:
    """The signatures of ``series`` (variable -> values on ``exp.pv``) keyed ``name`` or ``name:<slug>``."""
    pv, slugs = exp.pv, exp.schedule.slugs
    ends = exp.slug_ends()
    starts = np.concatenate(([0.0], ends[:-1]))
    nan = float("nan")
    out: dict[str, float] = {}
    oc = series.get("oil_cut")
    if oc is not None:
        above = np.flatnonzero(oc >= 0.5)
        out["water_breakthrough"] = _crossing(pv, oc, 0.5, int(above[0]) + 1, False) if above.size else nan
        chem = [i for i, s in enumerate(slugs) if s.surfactant_ppm > 0]
        if chem:
            i0 = int(np.searchsorted(pv, starts[chem[0]] - 1e-9))
            base = oc[i0] if i0 < pv.size and np.isfinite(oc[i0]) else nan
            out["oil_bank"] = _crossing(pv, oc, base + 0.05, i0 + 1, True) if np.isfinite(base) else nan
    dp = series.get("dp")
    if dp is not None:
        plateaus = [_plateau(pv, dp, lo, hi) for lo, hi in zip(starts, ends)]
        out.update({f"plateau_dp:{s.name}": p for s, p in zip(slugs, plateaus)})
        poly = [i for i, s in enumerate(slugs) if s.polymer_ppm > 0]
        after = [i for i in range(poly[-1] + 1, len(slugs)) if slugs[i].polymer_ppm == 0] if poly else []
        if after and len(slugs) > 1:
            out["rrf"] = plateaus[after[-1]] / plateaus[0] if plateaus[0] else nan
    rec = series.get("recovery")
    if rec is not None:
        for s, lo, hi in zip(slugs, starts, ends):
            out[f"incremental_recovery:{s.name}"] = _at(pv, rec, hi) - _at(pv, rec, lo)
    return out


def predictive_pvalues(exp: Experiment, observed: dict[str, np.ndarray], replicates: list[dict[str, np.ndarray]],
                       ) -> dict[str, tuple[float, float]]:
    """Per signature: (observed value, two-sided predictive p-value over ``replicates``); NaN where undefined."""
    obs = signatures(exp, observed)
    reps = [signatures(exp, r) for r in replicates]
    out = {}
    for key, t in obs.items():
        values = np.array([r.get(key, np.nan) for r in reps])
        values = values[np.isfinite(values)]
        if not np.isfinite(t) or values.size == 0:
            out[key] = (t, float("nan"))
            continue
        lower = (np.sum(values <= t) + 1) / (values.size + 1)
        upper = (np.sum(values >= t) + 1) / (values.size + 1)
        out[key] = (t, float(min(1.0, 2 * min(lower, upper))))
    return out
