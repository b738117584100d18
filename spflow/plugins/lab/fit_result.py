"""Weighted nonlinear least squares for the lab fits, returned as a FIT dataset with the parameter covariance.

The fit is :func:`scipy.optimize.least_squares` (trust-region reflective, bounds). The covariance is the Gauss-Newton
approximation at the optimum, ``C = s^2 (J^T J)^-1``, evaluated through the SVD of ``J`` (as
:func:`scipy.optimize.curve_fit` does):

* noise estimated (``sigma=None``): ``J`` of the residuals and ``s^2 = RSS / (n - p)``; intervals use Student's t
  with ``n - p`` degrees of freedom;
* noise known (``sigma`` given): residuals divided by ``sigma``, ``s^2 = 1``; intervals use the normal distribution.

The linearised interval ``estimate -/+ q std`` is exact only for a model linear in its parameters. With
``profile=True`` the fit also computes **profile-likelihood intervals** (:func:`profile_interval`): for each parameter
the set of values where the RSS, minimised over the other parameters inside their bounds, stays below
``RSS_min (1 + t^2/(n - p))`` (estimated noise, the F(1, n - p) test; ``t`` the Student quantile) or
``RSS_min + z^2`` (known noise, the chi^2(1) test). For a linear model both equal the linearised interval; for a
nonlinear one they follow the actual sum of squares, and they end at a parameter bound when the profile is still
below the threshold there (a Langmuir salinity slope estimated at 0 gets ``[0, upper]`` instead of a linearised
interval reaching negative values the forward model cannot take). The FIT dataset then carries
``profile_lower``/``profile_upper`` and attrs ``stated_interval = "profile"``; :func:`stated_interval` returns the
interval a fit states as its uncertainty.

Parameter names are the forward model's UTCHEM names where one exists (``spflow list params``), so the priors stage
can map a FIT dataset onto the forward model's parameter space.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np
import xarray as xr

from spflow.core.cf_metadata import UNITS_VARIABLE, product_unit, udunits
from spflow.core.errors import SpflowError
from spflow.core.schema import DatasetSchema, Variable

__all__ = ["FitError", "FIT", "unit_variables", "fit_least_squares", "fit_interval", "profile_interval",
           "stated_interval"]

#: Schema of every lab-fit stage output (extra variables on their own dims carry the data and the fitted curves).
#: Estimates, standard errors and profile bounds have units per parameter (``unit``), the covariance units per pair
#: of parameters (``covariance_units``), both UDUNITS (:mod:`spflow.core.cf_metadata`, :func:`unit_variables`).
FIT = DatasetSchema(
    dims=("param",),
    variables={
        "estimate": Variable(("param",), units_variable="unit", long_name="least-squares estimate",
                             doc="least-squares estimate (units per parameter: variable unit)"),
        "std": Variable(("param",), units_variable="unit", long_name="standard error of the estimate",
                        doc="standard error, sqrt of the covariance diagonal"),
        "covariance": Variable(("param", "param_"), units_variable="covariance_units",
                               long_name="covariance of the estimates", doc="Gauss-Newton covariance s^2 (J^T J)^-1"),
        "unit": Variable(("param",), kind="U", long_name="UDUNITS unit of each parameter",
                         doc="UDUNITS unit of each parameter"),
        "covariance_units": Variable(("param", "param_"), kind="U",
                                     long_name="UDUNITS unit of each covariance entry",
                                     doc="product of the units of the two parameters"),
        "profile_lower": Variable(("param",), units_variable="unit", required=False, allow_nan=True,
                                  long_name="lower end of the profile-likelihood interval",
                                  doc="lower end of the profile-likelihood interval (attrs interval_level; -inf = "
                                      "not bounded by the data)"),
        "profile_upper": Variable(("param",), units_variable="unit", required=False, allow_nan=True,
                                  long_name="upper end of the profile-likelihood interval",
                                  doc="upper end of the profile-likelihood interval (+inf = not bounded by the data)"),
    },
    attrs=("n_points", "dof", "rss", "reduced_chi2", "method", "kind", "experiment"),
    doc="lab fit: estimates, standard errors and covariance of sub-model parameters",
)


def unit_variables(units: Sequence[str]) -> dict[str, tuple]:
    """The unit variables of a FIT dataset for parameters in ``units`` (the forward model's catalogue notation or
    UDUNITS): ``unit`` (``param``), each parameter's UDUNITS unit (:func:`~spflow.core.cf_metadata.udunits`), and
    ``covariance_units`` (``param``, ``param_``), the product of the units of each pair (``meq/ml`` is written
    ``mmol/ml``; the executor adds the ``equivalents`` note, :func:`~spflow.core.cf_metadata.note_units`)."""
    unit = [udunits(u) for u in units]
    return {"unit": ("param", np.array(unit, dtype=str), {"long_name": "UDUNITS unit of each parameter"}),
            "covariance_units": (("param", "param_"), np.array([[product_unit(a, b) for b in unit] for a in unit],
                                                                 dtype=str),
                                 {"long_name": "UDUNITS unit of each covariance entry"})}


class FitError(SpflowError, ValueError):
    """A lab fit cannot be set up (bad inputs) or did not produce a usable result."""


def _bounds(bounds, names: Sequence[str]) -> tuple[np.ndarray, np.ndarray]:
    if len(bounds) != len(names):
        raise FitError(f"bounds: {len(bounds)} (low, high) pairs for {len(names)} parameters {list(names)}")
    lo = np.empty(len(names))
    hi = np.empty(len(names))
    for i, (name, pair) in enumerate(zip(names, bounds)):
        try:
            low, high = pair
        except (TypeError, ValueError):
            raise FitError(f"bounds of {name!r} must be a (low, high) pair, got {pair!r}") from None
        lo[i] = -np.inf if low is None else float(low)
        hi[i] = np.inf if high is None else float(high)
        if not lo[i] < hi[i]:
            raise FitError(f"bounds of {name!r}: low {float(lo[i])!r} must be < high {float(hi[i])!r}")
    return lo, hi


def _covariance(jac: np.ndarray, names: Sequence[str]) -> np.ndarray:
    """``(J^T J)^-1`` via the SVD of ``J``; a rank-deficient ``J`` raises naming the unidentified combination."""
    _, s, vt = np.linalg.svd(jac, full_matrices=False)
    threshold = np.finfo(float).eps * max(jac.shape) * (s[0] if s.size else 0.0)
    if s.size < len(names) or not s[-1] > threshold:
        null = vt[-1]
        worst = [names[i] for i in np.argsort(-np.abs(null))[:2]]
        raise FitError(
            f"parameters not identifiable from these data (Jacobian rank deficient); the data do not constrain the "
            f"combination dominated by {', '.join(worst)}"
        )
    return (vt.T / s**2) @ vt


def fit_least_squares(
    residuals: Callable[[np.ndarray], np.ndarray],
    x0,
    *,
    names: Sequence[str],
    units: Sequence[str],
    bounds: Sequence[tuple[float | None, float | None]],
    sigma=None,
    experiment: str = "",
    kind: str = "",
    profile: bool = False,
    level: float = 0.95,
) -> xr.Dataset:
    """Fit ``theta`` minimising ``sum(residuals(theta)**2)`` (weighted by ``1/sigma`` when given); a FIT dataset.

    ``residuals(theta)`` returns the 1-D array of ``(model - data) / scale``; ``x0``, ``names``, ``units`` and
    ``bounds`` (one ``(low, high)`` pair per parameter, ``None`` = unbounded) describe the parameters; ``sigma`` is
    a positive scalar or one value per residual (known noise standard deviation in the residual's scale).
    Returns ``estimate``, ``std``, ``covariance`` and their units (:func:`unit_variables`: ``unit``,
    ``covariance_units``) on dims ``param``/``param_`` with attrs ``units_<name>`` (each unit as given),
    ``n_points``, ``dof``, ``rss`` (weighted), ``reduced_chi2 = rss/dof``, ``noise`` ("estimated"/"known"),
    ``method``, ``nfev``, ``kind``, ``experiment``, ``interval_level`` (= ``level``) and ``stated_interval``:
    "linearised" (``estimate -/+ q std``), or with ``profile=True`` "profile", the profile-likelihood interval of
    every parameter at ``level`` in ``profile_lower``/``profile_upper``.
    """
    if not 0.0 < level < 1.0:
        raise FitError(f"level = {level!r} must be in (0, 1)")
    names = [str(n) for n in names]
    x0 = np.atleast_1d(np.asarray(x0, dtype=float))
    if x0.ndim != 1 or x0.size != len(names):
        raise FitError(f"x0 has shape {x0.shape}, expected ({len(names)},) for parameters {names}")
    if len(set(names)) != len(names):
        raise FitError(f"parameter names must be unique, got {names}")
    if len(units) != len(names):
        raise FitError(f"units: {len(units)} entries for {len(names)} parameters {names}")
    lo, hi = _bounds(bounds, names)
    for name, x, low, high in zip(names, x0, lo, hi):
        if not (np.isfinite(x) and low <= x <= high):
            raise FitError(
                f"starting value of {name!r} = {float(x)!r} must be finite and inside [{float(low)!r}, {float(high)!r}]"
            )

    r0 = np.asarray(residuals(x0), dtype=float)
    if r0.ndim != 1:
        raise FitError(f"residuals must return a 1-D array, got shape {r0.shape}")
    n, p = r0.size, len(names)
    if n <= p:
        raise FitError(f"{n} residuals for {p} parameters {names}: need more data points than parameters")
    if sigma is None:
        weight = np.ones(n)
    else:
        sig = np.asarray(sigma, dtype=float)
        if sig.ndim == 0:
            sig = np.full(n, float(sig))
        if sig.shape != (n,) or not (np.all(np.isfinite(sig)) and np.all(sig > 0)):
            raise FitError(f"sigma must be a positive finite scalar or {n} positive finite values")
        weight = 1.0 / sig
    if not np.all(np.isfinite(r0)):
        raise FitError(f"residuals are not finite at the starting point {dict(zip(names, x0))}")

    def weighted(theta):
        return np.asarray(residuals(theta), dtype=float) * weight

    res = _least_squares(weighted, x0, lo, hi)
    if res.status <= 0 or not np.all(np.isfinite(res.fun)):
        raise FitError(f"least-squares fit did not converge: {res.message}")
    dof = n - p
    rss = float(res.fun @ res.fun)
    s2 = rss / dof if sigma is None else 1.0
    cov = s2 * _covariance(res.jac, names)
    ds = xr.Dataset(
        {
            "estimate": ("param", res.x.copy(), {UNITS_VARIABLE: "unit"}),
            "std": ("param", np.sqrt(np.diag(cov)), {UNITS_VARIABLE: "unit"}),
            "covariance": (("param", "param_"), cov, {UNITS_VARIABLE: "covariance_units"}),
            **unit_variables(units),
        },
        coords={"param": names, "param_": names},
    )
    ds.attrs.update({f"units_{name}": str(unit) for name, unit in zip(names, units)})
    ds.attrs.update(
        n_points=n, dof=dof, rss=rss, reduced_chi2=rss / dof, noise="estimated" if sigma is None else "known",
        method="scipy.optimize.least_squares trf, 3-point Jacobian; covariance s^2 (J^T J)^-1",
        nfev=int(res.nfev), kind=str(kind), experiment=str(experiment), interval_level=float(level),
        stated_interval="linearised",
    )
    if profile:
        q = _quantile(ds.attrs["noise"], dof, level)
        threshold = rss * (1.0 + q**2 / dof) if sigma is None else rss + q**2
        if threshold > rss:
            ends = np.array([profile_interval(weighted, res.x, j, lo, hi, threshold, step=q * float(ds["std"][j]),
                                              name=names[j]) for j in range(p)])
        else:  # exact fit with estimated noise (RSS = 0): zero-width intervals, as std = 0
            ends = np.column_stack([res.x, res.x])
        ds["profile_lower"] = ("param", ends[:, 0], {UNITS_VARIABLE: "unit"})
        ds["profile_upper"] = ("param", ends[:, 1], {UNITS_VARIABLE: "unit"})
        ds.attrs.update(stated_interval="profile", profile_threshold_rss=float(threshold),
                        method=ds.attrs["method"] + "; profile-likelihood intervals (least_squares + brentq)")
    return ds


def _least_squares(fun, x0, lo, hi):
    """The one least-squares call of this module (trust-region reflective, 3-point Jacobian, tight tolerances)."""
    from scipy import optimize  # SciPy's optimisers load when a fit runs

    return optimize.least_squares(fun, x0, bounds=(lo, hi), method="trf", jac="3-point", x_scale="jac",
                                  ftol=1e-12, xtol=1e-12, gtol=1e-12, max_nfev=200 * (len(x0) + 1))


def _quantile(noise: str, dof: int, level: float) -> float:
    """Two-sided ``level`` quantile: normal for known noise, Student's t with ``dof`` when estimated."""
    tail = 0.5 + 0.5 * level
    from scipy import stats

    return float(stats.norm.ppf(tail) if noise == "known" else stats.t.ppf(tail, dof))


def profile_interval(weighted: Callable[[np.ndarray], np.ndarray], x_hat, j: int, lo, hi, threshold: float, *,
                     step: float, name: str = "", max_doublings: int = 30) -> tuple[float, float]:
    """Profile-likelihood interval ``{v : min_{theta_-j} RSS(theta_j = v) <= threshold}`` of parameter ``j``.

    ``weighted`` returns the weighted residuals, ``x_hat`` is the least-squares optimum, ``lo``/``hi`` the bounds.
    At each trial value the other parameters are re-optimised by :func:`scipy.optimize.least_squares` inside their
    bounds (warm-started from the nearest value already profiled). Each end is bracketed by stepping outward from
    the estimate by ``step`` (the linearised half-width), doubling the step, and then located by
    :func:`scipy.optimize.brentq`; an end whose bound is reached with the profiled RSS still below the threshold
    is the bound itself, one the data never bound is ``-/+inf``.
    """
    from scipy import optimize

    x_hat = np.asarray(x_hat, dtype=float)
    rest = np.arange(x_hat.size) != j
    starts = {float(x_hat[j]): x_hat[rest]}
    values: dict[float, float] = {}

    def excess(v: float) -> float:
        """Profiled RSS at ``theta_j = v`` minus the threshold (memoised: brentq re-evaluates the bracket ends, whose
        signs must not change with the warm start)."""
        if v in values:
            return values[v]
        if not rest.any():
            r = weighted(np.array([v]))
        else:
            near = min(starts, key=lambda u: abs(u - v))
            sub = _least_squares(lambda z: weighted(np.insert(z, j, v)), starts[near], lo[rest], hi[rest])
            starts[v] = sub.x
            r = sub.fun
        values[v] = float(r @ r) - threshold
        return values[v]

    if not excess(float(x_hat[j])) < 0.0:
        raise FitError(f"profile of {name!r}: the optimum is not below the threshold RSS {threshold!r}")
    if not (np.isfinite(step) and step > 0.0):
        raise FitError(f"profile of {name!r}: step {step!r} must be finite and > 0")
    ends = []
    for direction, bound in ((-1.0, lo[j]), (1.0, hi[j])):
        inside, h = float(x_hat[j]), step
        end = None
        for _ in range(max_doublings):
            if inside == bound:
                end = bound
                break
            trial = float(np.clip(x_hat[j] + direction * h, lo[j], hi[j]))
            if excess(trial) > 0.0:
                end = optimize.brentq(excess, inside, trial, xtol=1e-9 * step, rtol=1e-10)
                break
            inside, h = trial, 2.0 * h
        ends.append(direction * np.inf if end is None else float(end))
    return ends[0], ends[1]


def fit_interval(fit: xr.Dataset, level: float = 0.95) -> tuple[xr.DataArray, xr.DataArray]:
    """Two-sided ``level`` confidence interval of each parameter: ``estimate -/+ q std``.

    ``q`` is Student's t quantile with ``dof`` degrees of freedom when the noise was estimated, the normal quantile
    when it was known (attrs ``noise``).
    """
    if not 0.0 < level < 1.0:
        raise FitError(f"level = {level!r} must be in (0, 1)")
    q = _quantile(fit.attrs.get("noise"), fit.attrs["dof"], level)
    return fit["estimate"] - q * fit["std"], fit["estimate"] + q * fit["std"]


def stated_interval(fit: xr.Dataset) -> tuple[xr.DataArray, xr.DataArray]:
    """The interval a fit states as its uncertainty (attrs ``stated_interval``, level ``interval_level``): the
    profile-likelihood interval when the fit computed one for that purpose, otherwise :func:`fit_interval`."""
    if fit.attrs.get("stated_interval") == "profile":
        return fit["profile_lower"], fit["profile_upper"]
    return fit_interval(fit, float(fit.attrs.get("interval_level", 0.95)))
