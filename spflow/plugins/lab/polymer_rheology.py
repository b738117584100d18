"""Polymer rheology fit: shear sweeps at several concentrations and brines -> Eqs. 2.1-2.5 (thesis section 2.3).

Lab table (kind ``polymer_rheology``): one row per (sweep, shear rate) with columns ``c_polymer`` (wt %),
``anions`` and ``divalent`` (meq/ml, the brine's C51 and C61), ``shear_rate`` (1/s) and ``viscosity`` (cP); header
metadata ``water_viscosity`` (cP, the brine viscosity mu_w at the same temperature, section 2.3).

Model (the forward simulator's own kernels, not a re-implementation):
``C_SEP = C51 + (BETAP - 1) C61`` (Eq. 2.3, ``C11 = 1``), ``mu_p0`` Flory-Huggins with ``C_SEP^SSLOPE`` (Eqs. 2.1-2.2),
``gamma_half = (A1 C_SEP + A0) exp(A2 Cp)`` (Eq. 2.5), Meter law ``mu_p(gamma)`` (Eq. 2.4). All nine parameters
``AP1, AP2, AP3, SSLOPE, BETAP, POWN, A0, A1, A2`` are fitted jointly to every viscosity reading, with
log-residuals (rheometer error is relative). The thesis's stepwise procedure -- one Meter fit per sweep giving
``mu_p0`` and ``gamma_half`` points (Figs. 2.2, 2.3), then Eqs. 2.1-2.3 and 2.5 fitted to those points -- provides the
starting values and the points of the figures.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
import xarray as xr

from spflow.plugins.forward.parameters import PARAMETERS

from .fit_result import FitError, fit_least_squares
from .lab_table import lab_meta

__all__ = ["KIND", "COLUMNS", "NAMES", "rheology_viscosity", "fit_rheology", "synthetic_rheology"]

KIND = "polymer_rheology"
COLUMNS = {
    "c_polymer": ("wt%", "ppm"),
    "anions": ("meq/ml", "meq/l"),
    "divalent": ("meq/ml", "meq/l"),
    "shear_rate": ("1/s", "s^-1", "1/min"),
    "viscosity": ("cP", "mPa.s", "Pa.s"),
}
#: fitted parameters (forward-model UTCHEM names), in this order
NAMES = ("AP1", "AP2", "AP3", "SSLOPE", "BETAP", "POWN", "A0", "A1", "A2")
_SPEC = {s.name: s for s in PARAMETERS}


def rheology_viscosity(theta: Mapping[str, float], cp, c51, c61, gamma, mu_w: float, cse1: float) -> np.ndarray:
    """Polymer-solution viscosity (cP) at ``cp`` (wt %), brine ``c51``/``c61`` (meq/ml), shear rate ``gamma``
    (1/s) for the parameters ``theta`` (``NAMES``), Eqs. 2.1-2.5; ``mu_w`` in cP, ``cse1`` in meq/ml."""
    from .lab_kernels import viscosity_loop  # numba: compiled on first use, not when the stage is declared

    arrays = np.broadcast_arrays(*(np.asarray(a, dtype=float) for a in (cp, c51, c61, gamma)))
    flat = [np.ascontiguousarray(a.ravel()) for a in arrays]
    out = viscosity_loop(*flat, float(mu_w), float(cse1), *(float(theta[n]) for n in NAMES))
    return out.reshape(arrays[0].shape)


def _sweeps(data: xr.Dataset) -> tuple[np.ndarray, np.ndarray]:
    """Sweep index per point (unique concentration and brine) and the (n_sweep, 3) table of those keys."""
    keys = np.column_stack([data["c_polymer"].values, data["anions"].values, data["divalent"].values])
    table, index = np.unique(keys, axis=0, return_inverse=True)
    return index.ravel(), table


def _sweep_fits(data, index, table, mu_w):
    """Per-sweep Meter fits (mu_p0, gamma_half, POWN), the thesis's points of Figs. 2.2-2.3."""
    from .lab_kernels import meter_loop

    out = np.empty((table.shape[0], 3))
    std = np.empty_like(out)
    for s in range(table.shape[0]):
        sel = index == s
        gamma, mu = data["shear_rate"].values[sel], data["viscosity"].values[sel]
        if gamma.size < 4:
            raise FitError(f"sweep {s} (c_polymer={table[s, 0]:g} wt%) has {gamma.size} points, need >= 4")
        mu0_guess = float(mu.max())
        half = 0.5 * (mu0_guess + mu_w)
        ghalf_guess = float(np.interp(-half, -mu[np.argsort(gamma)], np.sort(gamma)))
        fit = fit_least_squares(
            lambda t, g=gamma, m=mu: np.log(meter_loop(mu_w, t[0], g, t[1], t[2]) / m),
            [mu0_guess, max(ghalf_guess, 1e-3), 1.7], names=["mu0", "gamma_half", "POWN"],
            units=["cP", "1/s", "1"], bounds=[(mu_w * (1 + 1e-6), None), (1e-6, None), (1.0 + 1e-6, 5.0)],
        )
        out[s] = fit["estimate"].values
        std[s] = fit["std"].values
    return out, std


def _starting_values(table, sweep, mu_w, cse1) -> dict[str, float]:
    """Eqs. 2.1-2.3 fitted to the per-sweep mu_p0 and Eq. 2.5 to the per-sweep gamma_half (thesis procedure)."""
    cp, c51, c61 = table.T
    mu0, ghalf, pown = sweep.T
    start = {"POWN": float(np.median(pown))}
    names = ["AP1", "AP2", "AP3", "SSLOPE", "BETAP"]
    zero = fit_least_squares(
        lambda t: np.log(rheology_viscosity(dict(zip(names, t), POWN=2.0, A0=1.0, A1=0.0, A2=0.0),
                                            cp, c51, c61, 0.0, mu_w, cse1) / mu0),
        [10.0, 0.0, 100.0, -0.5, 1.0], names=names, units=["1"] * 5, bounds=[_bounds(n) for n in names],
    )
    start.update(zip(names, zero["estimate"].values.tolist()))
    csep = np.maximum(c51 + (start["BETAP"] - 1.0) * c61, cse1)
    a_names = ["A0", "A1", "A2"]
    half = fit_least_squares(
        lambda t: np.log(np.maximum((t[1] * csep + t[0]) * np.exp(t[2] * cp), 1e-300) / ghalf),
        [0.0, float(np.mean(ghalf / csep)), 0.0], names=a_names, units=["1"] * 3,
        bounds=[_bounds(n) for n in a_names],
    )
    start.update(zip(a_names, half["estimate"].values.tolist()))
    return start


def _bounds(name: str) -> tuple[float, float]:
    spec = _SPEC[name]
    return spec.lower, spec.upper


def fit_rheology(data: xr.Dataset, *, cse1: float = _SPEC["CSE1"].default) -> xr.Dataset:
    """Joint fit of ``NAMES`` to a rheology lab table (see the module docstring); a FIT dataset.

    Extra variables: the lab data and the fitted viscosity on ``point``; per-sweep Meter fits ``sweep_mu0``,
    ``sweep_gamma_half``, ``sweep_pown`` (with ``*_std``), the sweep keys (``sweep_c_polymer``, ``sweep_anions``,
    ``sweep_divalent``) and the fitted ``sweep_csep`` on ``sweep``.
    """
    mu_w = lab_meta(data, "water_viscosity", ("cP", "mPa.s", "Pa.s"))
    cp, c51, c61 = (data[v].values for v in ("c_polymer", "anions", "divalent"))
    gamma, mu = data["shear_rate"].values, data["viscosity"].values
    for name, values in (("c_polymer", cp), ("shear_rate", gamma), ("viscosity", mu)):
        if not np.all(values > 0):
            raise FitError(f"lab table {data.attrs.get('source')!r}: column {name!r} must be > 0 everywhere")
    if not np.all(mu > mu_w):
        raise FitError(f"lab table {data.attrs.get('source')!r}: every viscosity must exceed water_viscosity {mu_w}")
    index, table = _sweeps(data)
    sweep, sweep_std = _sweep_fits(data, index, table, mu_w)
    start = _starting_values(table, sweep, mu_w, cse1)
    x0 = [min(max(start[n], _bounds(n)[0]), _bounds(n)[1]) for n in NAMES]

    def residuals(t):
        return np.log(rheology_viscosity(dict(zip(NAMES, t)), cp, c51, c61, gamma, mu_w, cse1) / mu)

    fit = fit_least_squares(residuals, x0, names=NAMES, units=[_SPEC[n].unit for n in NAMES],
                            bounds=[_bounds(n) for n in NAMES], experiment=data.attrs.get("experiment", ""),
                            kind=KIND)
    est = dict(zip(NAMES, fit["estimate"].values))
    for v in COLUMNS:
        fit[v] = data[v]
    fit["viscosity_fit"] = ("point", rheology_viscosity(est, cp, c51, c61, gamma, mu_w, cse1), {"units": "cP"})
    fit["sweep_c_polymer"] = ("sweep", table[:, 0], {"units": "wt%"})
    fit["sweep_anions"] = ("sweep", table[:, 1], {"units": "meq/ml"})
    fit["sweep_divalent"] = ("sweep", table[:, 2], {"units": "meq/ml"})
    fit["sweep_csep"] = ("sweep", np.maximum(table[:, 1] + (est["BETAP"] - 1.0) * table[:, 2], cse1),
                         {"units": "meq/ml"})
    for j, (name, unit) in enumerate((("mu0", "cP"), ("gamma_half", "1/s"), ("pown", "1"))):
        fit[f"sweep_{name}"] = ("sweep", sweep[:, j], {"units": unit})
        fit[f"sweep_{name}_std"] = ("sweep", sweep_std[:, j], {"units": unit})
    fit.attrs.update(water_viscosity_cp=mu_w, cse1_meq_ml=float(cse1), source=data.attrs.get("source", ""))
    return fit


#: bundled design: HPAM concentrations (wt %), brines (TDS ppm, divalent multiple of the Table 2.1 share), shear rates
DESIGN_CP = (0.05, 0.1, 0.15, 0.2, 0.25)
DESIGN_BRINES = ((9400.0, 1.0), (15000.0, 1.0), (22000.0, 1.0), (15000.0, 5.0))
DESIGN_SHEAR = tuple(np.geomspace(0.1, 1000.0, 13).tolist())


def synthetic_rheology(truth: Mapping[str, float], rng: np.random.Generator | None, *, noise: float = 0.02,
                       mu_w: float = 1.0, cse1: float = _SPEC["CSE1"].default) -> xr.Dataset:
    """Lab-like shear sweeps on the bundled design from the model with parameters ``truth`` (``NAMES``).

    Readings get multiplicative log-normal noise of relative size ``noise`` (rheometer error; ``rng=None`` or
    ``noise=0``: exact). Brine compositions follow the forward model's TDS conversion (Table 2.1 brine scaled).
    """
    from spflow.plugins.forward import units

    rows = [(cp, units.tds_ppm_to_anions(tds), units.tds_ppm_to_divalent(tds) * hard, g)
            for tds, hard in DESIGN_BRINES for cp in DESIGN_CP for g in DESIGN_SHEAR]
    cp, c51, c61, gamma = (np.array(col) for col in zip(*rows))
    mu = rheology_viscosity(truth, cp, c51, c61, gamma, mu_w, cse1)
    if rng is not None and noise > 0:
        mu = mu * np.exp(rng.normal(0.0, noise, mu.size))
    ds = xr.Dataset({name: ("point", values) for name, values in
                     zip(COLUMNS, (cp, c51, c61, gamma, mu))})
    for name, allowed in COLUMNS.items():
        ds[name].attrs["units"] = allowed[0]
    ds.attrs.update(kind=KIND, experiment="HPAM shear sweeps (synthetic)",
                    meta_water_viscosity=f"{mu_w:g} cP", meta_noise=f"{noise:g} relative (log-normal)")
    return ds
