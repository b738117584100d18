"""Weighted nonlinear least squares for the lab fits, returned as a FIT dataset with the parameter covariance.

The fit is :func:`scipy.optimize.least_squares` (trust-region reflective, bounds). The covariance is the Gauss-Newton
approximation at the optimum, ``C = s^2 (J^T J)^-1``, evaluated through the SVD of ``J`` (as
:func:`scipy.optimize.curve_fit` does):

* noise estimated (``sigma=None``): ``J`` of the residuals and ``s^2 = RSS / (n - p)``; intervals use Student's t
  with ``n - p`` degrees of freedom;
* noise known (``sigma`` given): residuals divided by ``sigma``, ``s^2 = 1``; intervals use the normal distribution.

Parameter names are the forward model's UTCHEM names where one exists (``spflow list params``), so the priors stage
can map a FIT dataset onto the forward model's parameter space.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np
import xarray as xr
from scipy import optimize, stats

from spflow.core.errors import SpflowError
from spflow.core.schema import DatasetSchema, Variable

__all__ = ["FitError", "FIT", "fit_least_squares", "fit_interval"]

#: Schema of every lab-fit stage output (extra variables on their own dims carry the data and the fitted curves).
FIT = DatasetSchema(
    dims=("param",),
    variables={
        "estimate": Variable(("param",), doc="least-squares estimate (units: attrs units_<name> / variable unit)"),
        "std": Variable(("param",), doc="standard error, sqrt of the covariance diagonal"),
        "covariance": Variable(("param", "param_"), doc="Gauss-Newton covariance s^2 (J^T J)^-1"),
        "unit": Variable(("param",), kind="U", doc="unit of each parameter"),
    },
    attrs=("n_points", "dof", "rss", "reduced_chi2", "method", "kind", "experiment"),
    doc="lab fit: estimates, standard errors and covariance of sub-model parameters",
)


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
) -> xr.Dataset:
    """Fit ``theta`` minimising ``sum(residuals(theta)**2)`` (weighted by ``1/sigma`` when given); a FIT dataset.

    ``residuals(theta)`` returns the 1-D array of ``(model - data) / scale``; ``x0``, ``names``, ``units`` and
    ``bounds`` (one ``(low, high)`` pair per parameter, ``None`` = unbounded) describe the parameters; ``sigma`` is
    a positive scalar or one value per residual (known noise standard deviation in the residual's scale).
    Returns ``estimate``, ``std``, ``covariance`` and ``unit`` on dims ``param``/``param_`` with attrs
    ``units_<name>``, ``n_points``, ``dof``, ``rss`` (weighted), ``reduced_chi2 = rss/dof``, ``noise``
    ("estimated"/"known"), ``method``, ``nfev``, ``kind``, ``experiment``.
    """
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

    res = optimize.least_squares(weighted, x0, bounds=(lo, hi), method="trf", jac="3-point", x_scale="jac",
                                 ftol=1e-12, xtol=1e-12, gtol=1e-12, max_nfev=200 * (p + 1))
    if res.status <= 0 or not np.all(np.isfinite(res.fun)):
        raise FitError(f"least-squares fit did not converge: {res.message}")
    dof = n - p
    rss = float(res.fun @ res.fun)
    s2 = rss / dof if sigma is None else 1.0
    cov = s2 * _covariance(res.jac, names)
    ds = xr.Dataset(
        {
            "estimate": ("param", res.x.copy()),
            "std": ("param", np.sqrt(np.diag(cov))),
            "covariance": (("param", "param_"), cov),
            "unit": ("param", np.array([str(u) for u in units], dtype=str)),
        },
        coords={"param": names, "param_": names},
    )
    ds.attrs.update({f"units_{name}": str(unit) for name, unit in zip(names, units)})
    ds.attrs.update(
        n_points=n, dof=dof, rss=rss, reduced_chi2=rss / dof, noise="estimated" if sigma is None else "known",
        method="scipy.optimize.least_squares trf, 3-point Jacobian; covariance s^2 (J^T J)^-1",
        nfev=int(res.nfev), kind=str(kind), experiment=str(experiment),
    )
    return ds


def fit_interval(fit: xr.Dataset, level: float = 0.95) -> tuple[xr.DataArray, xr.DataArray]:
    """Two-sided ``level`` confidence interval of each parameter: ``estimate -/+ q std``.

    ``q`` is Student's t quantile with ``dof`` degrees of freedom when the noise was estimated, the normal quantile
    when it was known (attrs ``noise``).
    """
    if not 0.0 < level < 1.0:
        raise FitError(f"level = {level!r} must be in (0, 1)")
    tail = 0.5 + 0.5 * level
    q = stats.norm.ppf(tail) if fit.attrs.get("noise") == "known" else stats.t.ppf(tail, fit.attrs["dof"])
    return fit["estimate"] - q * fit["std"], fit["estimate"] + q * fit["std"]
