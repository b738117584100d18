"""Microemulsion viscosity vs composition fitted with the compositional law: ALPHAV1-5 (thesis section 2.7, Eq. 2.11,
Fig. 2.7).

Each measurement is the viscosity (cP) of a single-phase microemulsion of known water/oil/surfactant volume fractions
(``water``, ``oil``, ``surfactant``; normalised to sum 1). The fitted model is the forward simulator's kernel
:func:`spflow.plugins.forward.physics.microemulsion_viscosity.microemulsion_viscosity`
``mu = C1 mu_w e^(a1 (C2 + C3)) + C2 mu_o e^(a2 (C1 + C3)) + C3 a3 e^(a4 C1 + a5 C2)`` with the brine and oil
viscosities ``mu_w``, ``mu_o`` (VIS1, VIS2) read from the table's metadata ``vis1``/``vis2``.

``fit`` chooses which ALPHAVs are estimated; the others are held at ``fixed`` values (default: the forward model's
Table 2.4 values). With ``ALPHAV3 = 0`` the surfactant term vanishes and ALPHAV4/ALPHAV5 do not enter the model, so
they can only be fitted together with ALPHAV3 and data rich enough in surfactant to show that term (the least-squares
fit then reports which combination the data leave unconstrained). Rheometer errors are relative: residuals
``log mu_model - log mu_data`` with a common, estimated noise level.
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from spflow.plugins.forward.parameters import PARAMETERS
from spflow.plugins.lab.fit_result import FitError, fit_least_squares
from spflow.plugins.lab.lab_table import lab_meta, read_lab_table

__all__ = ["KIND", "COLUMNS", "NAMES", "viscosity_model", "read_me_viscosity_table", "synthetic_me_viscosity",
           "fit_me_viscosity"]

KIND = "me_viscosity"
_FRACTION_UNITS = ("fraction", "-", "%", "vol%")
#: required columns -> allowed units (canonical first)
COLUMNS = {"water": _FRACTION_UNITS, "oil": _FRACTION_UNITS, "surfactant": _FRACTION_UNITS,
           "viscosity": ("cP", "mPa.s", "Pa.s")}
#: all compositional-viscosity parameters
NAMES = ("ALPHAV1", "ALPHAV2", "ALPHAV3", "ALPHAV4", "ALPHAV5")
_SPEC = {p.name: p for p in PARAMETERS}
_VIS_UNITS = ("cP", "mPa.s", "Pa.s")


def viscosity_model(water, oil, surfactant, alphas, mu_w: float, mu_o: float) -> np.ndarray:
    """Eq. 2.11 (cP) at each composition; ``alphas`` = (ALPHAV1, ..., ALPHAV5)."""
    from spflow.plugins.forward.physics.microemulsion_viscosity import microemulsion_viscosity

    c1, c2, c3 = (np.asarray(c, dtype=float) for c in (water, oil, surfactant))
    a = [float(x) for x in alphas]
    return np.array([microemulsion_viscosity(x1, x2, x3, mu_w, mu_o, *a)
                     for x1, x2, x3 in zip(c1.ravel(), c2.ravel(), c3.ravel())]).reshape(c1.shape)


def _fluid_viscosities(ds: xr.Dataset) -> tuple[float, float]:
    where = f"lab table {ds.attrs.get('source', '')!r}"
    out = []
    for key, name in (("vis1", "VIS1"), ("vis2", "VIS2")):
        value = lab_meta(ds, key, _VIS_UNITS)
        spec = _SPEC[name]
        if not spec.lower <= value <= spec.upper:
            raise FitError(f"{where}: {key} = {value!r} cP outside the allowed range {spec.describe_range()}")
        out.append(value)
    return out[0], out[1]


def _check(ds: xr.Dataset) -> None:
    where = f"lab table {ds.attrs.get('source', '')!r}"
    comp = np.column_stack([ds[c].values for c in ("water", "oil", "surfactant")])
    bad = np.nonzero((comp < 0.0).any(axis=1) | (np.abs(comp.sum(axis=1) - 1.0) > 0.02))[0]
    if bad.size:
        raise FitError(f"{where}: data row {int(bad[0]) + 1}: water + oil + surfactant = {comp[bad[0]].sum():.4g} "
                       "must be 1 (within 0.02) with every fraction >= 0")
    low = ds["viscosity"].values <= 0.0
    if low.any():
        raise FitError(f"{where}: column 'viscosity' must be > 0 cP; data row {int(np.argmax(low)) + 1}")


def read_me_viscosity_table(path) -> xr.Dataset:
    """Read an ``me_viscosity`` lab table (columns water, oil, surfactant, viscosity; metadata ``vis1``, ``vis2``
    with a viscosity unit)."""
    ds = read_lab_table(path, KIND, COLUMNS)
    _fluid_viscosities(ds)
    _check(ds)
    return ds


def synthetic_me_viscosity(truth: dict[str, float], oil_fraction, surfactant, *, noise: float = 0.04, seed: int = 0,
                           experiment: str = "synthetic microemulsion viscosities") -> xr.Dataset:
    """Lab-like viscosities of single-phase MEs on a grid: surfactant fraction ``surfactant[j]`` and oil fraction
    ``oil_fraction[i]`` of the surfactant-free part; truth viscosities times ``exp(N(0, noise^2))``."""
    w, s = np.meshgrid(np.asarray(oil_fraction, dtype=float), np.asarray(surfactant, dtype=float))
    c3 = s.ravel()
    c2 = (1.0 - c3) * w.ravel()
    c1 = (1.0 - c3) * (1.0 - w.ravel())
    mu = viscosity_model(c1, c2, c3, [truth[n] for n in NAMES], truth["VIS1"], truth["VIS2"])
    mu *= np.exp(noise * np.random.default_rng(seed).standard_normal(mu.size))
    return xr.Dataset(
        {
            "water": ("point", c1, {"units": "fraction"}),
            "oil": ("point", c2, {"units": "fraction"}),
            "surfactant": ("point", c3, {"units": "fraction"}),
            "viscosity": ("point", mu, {"units": "cP"}),
        },
        attrs={"kind": KIND, "experiment": experiment, "meta_vis1": f"{truth['VIS1']:g} cP",
               "meta_vis2": f"{truth['VIS2']:g} cP"},
    )


def fit_me_viscosity(data: xr.Dataset, *, fit: tuple[str, ...] = NAMES, fixed: dict[str, float] | None = None,
                     curve_points: int = 150) -> xr.Dataset:
    """Fit the ALPHAVs named in ``fit`` to a table read by :func:`read_me_viscosity_table`; the others are held at
    ``fixed`` (default: the forward model's defaults).

    Returns the FIT dataset plus the data (``water``, ``oil``, ``surfactant``, ``viscosity`` and the oil
    solubilization ratio ``r_oil = oil/surfactant`` on dim ``point``) and the fitted viscosity along the oil fraction
    ratio at each measured surfactant fraction (``curve_viscosity`` on dims ``curve_surfactant``, ``curve_ratio``,
    log-spaced; NaN where the composition would need a negative water fraction).
    """
    fit = tuple(fit)
    unknown = [n for n in fit if n not in NAMES]
    if unknown or not fit or len(set(fit)) != len(fit):
        raise FitError(f"fit must be a non-empty list of distinct names among {list(NAMES)}, got {list(fit)}")
    fixed = dict(fixed or {})
    bad = [n for n in fixed if n not in NAMES or n in fit]
    if bad:
        raise FitError(f"fixed: {bad[0]!r} is not an ALPHAV held fixed (fitted: {list(fit)}; all: {list(NAMES)})")
    held = {n: float(fixed.get(n, _SPEC[n].default)) for n in NAMES if n not in fit}
    mu_w, mu_o = _fluid_viscosities(data)
    _check(data)
    c1, c2, c3 = (data[c].values for c in ("water", "oil", "surfactant"))
    log_data = np.log(data["viscosity"].values)
    index = [NAMES.index(n) for n in fit]

    def alphas(theta):
        full = np.array([held.get(n, 0.0) for n in NAMES])
        full[index] = theta
        return full

    def residuals(theta):
        return np.log(viscosity_model(c1, c2, c3, alphas(theta), mu_w, mu_o)) - log_data

    x0 = [1.0 for _ in fit]  # data-independent start inside every ALPHAV's range
    out = fit_least_squares(residuals, x0, names=fit, units=[_SPEC[n].unit for n in fit],
                            bounds=[(_SPEC[n].lower, _SPEC[n].upper) for n in fit],
                            experiment=data.attrs.get("experiment", ""), kind=KIND)
    levels = np.unique(np.round(c3, 12))
    ratio = c2 / c3
    grid = np.geomspace(max(ratio.min(), 1e-3) / 2.0, ratio.max() * 2.0, curve_points)
    best = alphas(out["estimate"].values)
    curves = np.full((levels.size, grid.size), np.nan)
    for j, level in enumerate(levels):
        ok = grid * level <= 1.0 - level  # water fraction >= 0
        oil = grid[ok] * level
        curves[j, ok] = viscosity_model(1.0 - level - oil, oil, np.full_like(oil, level), best, mu_w, mu_o)
    for col, values in (("water", c1), ("oil", c2), ("surfactant", c3)):
        out[col] = ("point", values, {"units": "fraction"})
    out["viscosity"] = ("point", data["viscosity"].values, {"units": "cP"})
    out["r_oil"] = ("point", ratio, {"units": "-", "long_name": "oil solubilization ratio C2/C3"})
    out = out.assign_coords(curve_surfactant=("curve_surfactant", levels, {"units": "fraction"}),
                            curve_ratio=("curve_ratio", grid, {"units": "-", "long_name": "C2/C3"}))
    out["curve_viscosity"] = (("curve_surfactant", "curve_ratio"), curves,
                              {"units": "cP", "long_name": "Eq. 2.11 fit (NaN where C1 < 0)"})
    out.attrs.update(vis1=mu_w, vis2=mu_o, fixed=str(held), residuals="log(mu_model) - log(mu_data)")
    return out
