"""Capillary desaturation curve (residual saturation vs capillary/trapping number) fitted for the trapping parameter
and the low/high residuals of one phase (thesis section 2.8, Eq. 2.12, Table 2.3, Fig. 2.8).

A CDC experiment floods a core at increasing rates (and lower IFT) and records the residual saturation of phase
``l`` left behind at each capillary number ``N = mu u / sigma`` (Eq. 1.1). The fitted model is the forward
simulator's kernel :func:`spflow.plugins.forward.physics.trapping.residual_saturation`
``S_lr = S_lr^high + (S_lr^low - S_lr^high) / (1 + T_l N^tau)`` with ``tau = 1`` as in the thesis and the simulator.
For 1-D horizontal floods without capillary pressure the capillary number equals the simulator's trapping number
(UTCHEM ITRAP 1 = 2, UTCHEM-9.0 User's Guide §3.4), so the fitted ``T_l`` is the forward model's.

The table's metadata ``phase`` (1 aqueous, 2 oleic -- the usual waterflood CDC of residual oil --, 3 microemulsion)
selects the names: ``T11, S1RWC, S1RC`` / ``T22, S2RWC, S2RC`` / ``T33, S3RWC, S3RC``. ``T_l`` spans decades and is
fitted as ``log10 T_l`` (its covariance is mapped back with the delta method); residual saturations come from
material balance with an absolute error, so residuals are ``S_model - S_data`` with an estimated noise level.
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from spflow.core.cf_metadata import UNITS_VARIABLE
from spflow.plugins.forward.parameters import PARAMETERS
from spflow.plugins.lab.fit_result import FitError, fit_least_squares, unit_variables
from spflow.plugins.lab.lab_table import lab_meta, read_lab_table

__all__ = ["KIND", "COLUMNS", "TAU", "phase_names", "desaturation_model", "read_desaturation_table",
           "synthetic_desaturation", "fit_desaturation"]

KIND = "desaturation"
#: required columns -> allowed units (canonical first)
COLUMNS = {"capillary_number": ("-", "1"), "residual_saturation": ("fraction", "-", "%")}
#: exponent of the trapping number in Eq. 2.12 (thesis: "We use a value of one for tau_l"; the simulator too)
TAU = 1.0
_SPEC = {p.name: p for p in PARAMETERS}


def phase_names(phase: int) -> tuple[str, str, str]:
    """Forward-model names ``(T_ll, S_lRWC, S_lRC)`` of phase 1 (aqueous), 2 (oleic) or 3 (microemulsion)."""
    if phase not in (1, 2, 3):
        raise FitError(f"phase = {phase!r} must be 1 (aqueous), 2 (oleic) or 3 (microemulsion)")
    return f"T{phase}{phase}", f"S{phase}RWC", f"S{phase}RC"


def desaturation_model(capillary_number, t_l: float, s_low: float, s_high: float) -> np.ndarray:
    """Eq. 2.12 (without ``min(S_l, .)``) at each capillary number via the forward model's kernel."""
    from spflow.plugins.forward.physics.trapping import residual_saturation

    n = np.asarray(capillary_number, dtype=float)
    return np.array([residual_saturation(s_low, s_high, t_l, x, TAU) for x in n.ravel()]).reshape(n.shape)


def _phase(ds: xr.Dataset) -> int:
    value = lab_meta(ds, "phase")
    if value not in (1.0, 2.0, 3.0):
        raise FitError(f"lab table {ds.attrs.get('source', '')!r} metadata 'phase': {value!r} must be 1 (aqueous), "
                       "2 (oleic) or 3 (microemulsion)")
    return int(value)


def _check(ds: xr.Dataset) -> None:
    where = f"lab table {ds.attrs.get('source', '')!r}"
    n, s = ds["capillary_number"].values, ds["residual_saturation"].values
    for col, values, ok, text in (("capillary_number", n, n > 0.0, "> 0"),
                                  ("residual_saturation", s, (s >= 0.0) & (s <= 1.0), "in [0, 1]")):
        if not ok.all():
            bad = int(np.argmin(ok))
            raise FitError(f"{where}: column {col!r} must be {text}; data row {bad + 1} has {float(values[bad]):g}")
    if np.unique(n).size < 4:
        raise FitError(f"{where}: need at least 4 distinct capillary numbers for 3 parameters")


def read_desaturation_table(path) -> xr.Dataset:
    """Read a ``desaturation`` lab table (columns capillary_number, residual_saturation; bare-number metadata
    ``phase``)."""
    ds = read_lab_table(path, KIND, COLUMNS)
    _phase(ds)
    _check(ds)
    return ds


def synthetic_desaturation(truth: dict[str, float], capillary_number, *, phase: int = 2, noise: float = 0.01,
                           seed: int = 0, experiment: str = "synthetic capillary desaturation") -> xr.Dataset:
    """Lab-like CDC: Eq. 2.12 with the truth's parameters of ``phase`` plus ``N(0, noise^2)`` (absolute saturation
    error), clipped to [0, 1]."""
    t_name, low, high = phase_names(phase)
    s = desaturation_model(capillary_number, truth[t_name], truth[low], truth[high])
    s = np.clip(s + noise * np.random.default_rng(seed).standard_normal(s.size), 0.0, 1.0)
    return xr.Dataset(
        {
            "capillary_number": ("point", np.asarray(capillary_number, dtype=float), {"units": "-"}),
            "residual_saturation": ("point", s, {"units": "fraction"}),
        },
        attrs={"kind": KIND, "experiment": experiment, "meta_phase": str(phase)},
    )


def fit_desaturation(data: xr.Dataset, *, curve_points: int = 200) -> xr.Dataset:
    """Fit ``(T_ll, S_lRWC, S_lRC)`` of the table's phase to a CDC read by :func:`read_desaturation_table`.

    The search runs in ``(log10 T_ll, S_lRWC, S_lRC)``; the returned FIT dataset is in the forward model's units
    (``T_ll`` and its covariance mapped back with the Jacobian ``dT/dlog10 T = T ln 10``). Extra variables: the data
    (``capillary_number``, ``residual_saturation`` on dim ``point``) and the fitted CDC (``curve_saturation`` on dim
    ``curve_capillary_number``, log-spaced one decade beyond the data).
    """
    _check(data)
    phase = _phase(data)
    names = phase_names(phase)
    n = data["capillary_number"].values
    s = data["residual_saturation"].values
    order = np.argsort(n)
    s_sorted = s[order]
    t_spec, low_spec, high_spec = (_SPEC[x] for x in names)
    # start: plateaus from the three lowest / highest N, T from the N where S crosses the plateaus' midpoint
    s_low0 = float(np.clip(np.mean(s_sorted[:3]), low_spec.lower, low_spec.upper))
    s_high0 = float(np.clip(np.mean(s_sorted[-3:]), high_spec.lower, min(high_spec.upper, s_low0)))
    mid = 0.5 * (s_low0 + s_high0)
    n_mid = float(n[order][np.argmin(np.abs(s_sorted - mid))])
    log_t_bounds = (-3.0, np.log10(t_spec.upper))
    x0 = [float(np.clip(-np.log10(n_mid), *log_t_bounds)), s_low0, s_high0]

    def residuals(theta):
        return desaturation_model(n, 10.0 ** theta[0], theta[1], theta[2]) - s

    raw = fit_least_squares(residuals, x0, names=["log10_" + names[0], names[1], names[2]],
                            units=["log10(-)", low_spec.unit, high_spec.unit],
                            bounds=[log_t_bounds, (low_spec.lower, low_spec.upper),
                                    (high_spec.lower, high_spec.upper)],
                            experiment=data.attrs.get("experiment", ""), kind=KIND)
    est = raw["estimate"].values.copy()
    t_hat = 10.0 ** est[0]
    jac = np.diag([t_hat * np.log(10.0), 1.0, 1.0])
    cov = jac @ raw["covariance"].values @ jac.T
    est[0] = t_hat
    units = [t_spec.unit, low_spec.unit, high_spec.unit]
    fit = xr.Dataset(
        {
            "estimate": ("param", est, {UNITS_VARIABLE: "unit"}),
            "std": ("param", np.sqrt(np.diag(cov)), {UNITS_VARIABLE: "unit"}),
            "covariance": (("param", "param_"), cov, {UNITS_VARIABLE: "covariance_units"}),
            **unit_variables(units),
        },
        coords={"param": list(names), "param_": list(names)},
        attrs={**raw.attrs, **{f"units_{k}": u for k, u in zip(names, units)}},
    )
    for key in [k for k in fit.attrs if k.startswith("units_log10_")]:
        del fit.attrs[key]
    fit.attrs.update(phase=phase, tau=TAU, log10_t_estimate=float(raw["estimate"].values[0]),
                     log10_t_std=float(raw["std"].values[0]), residuals="S_model - S_data",
                     method=raw.attrs["method"] + "; T fitted as log10 T, covariance by the delta method")
    grid = np.geomspace(n.min() / 10.0, n.max() * 10.0, curve_points)
    fit["capillary_number"] = ("point", n, {"units": "-"})
    fit["residual_saturation"] = ("point", s, {"units": "fraction"})
    fit = fit.assign_coords(curve_capillary_number=("curve_capillary_number", grid, {"units": "-"}))
    fit["curve_saturation"] = ("curve_capillary_number", desaturation_model(grid, *est), {"units": "fraction"})
    return fit
