"""Single-phase polymer coreflood fit: pressure history water -> polymer -> water -> PERM, BRK, CRK (section 2.4).

Lab table (kind ``polymer_coreflood``): columns ``pv`` (injected pore volumes), ``dp`` (pressure drop, Pa),
``c_polymer_in`` and ``salinity_in`` (ppm: the composition injected over the interval that ends at that row's
``pv``; a slug ends at the last row of its composition); metadata ``length``, ``diameter`` (m), ``porosity``,
``flow_rate`` (ml/min), ``water_viscosity`` (cP) of the core and brine of Table 2.2.

Model: the forward simulator itself (:func:`spflow.simulate`) on the water-filled core (``SWI = 1``, no residual
phases, ``k_rw = 1``), so the pressure history carries Darcy's law, Flory-Huggins and Meter viscosity (Eqs. 2.1-2.4),
the permeability reduction ``R_k`` of Eqs. 2.6-2.8 (irreversible), adsorption, IPV and dispersion exactly as in a
coreflood run. Fitted: the absolute permeability ``PERM`` (initial water flood; it also enters Eq. 2.8), ``BRK`` and
``CRK``; every other parameter is fixed (``fixed``: e.g. the rheology fit; default Table 2.4). The residuals are
``log(dp_model / dp_data)`` (transducer error is relative).

Identifiability: at one polymer concentration the plateaus give only ``R_k(C)`` (RF and RRF, Eq. 2.6), one number
for two parameters; the bundled test therefore injects three concentrations in increasing steps (R_k follows the
running maximum), which separates ``BRK`` (shape of ``R_k`` vs ``C``) from ``CRK`` (its ceiling ``R_k,max``).
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
import xarray as xr

from spflow.plugins.forward.parameters import PARAMETERS
from spflow.plugins.forward.simulate import simulate

from .fit_result import FitError, fit_least_squares
from .lab_table import lab_meta

__all__ = ["KIND", "COLUMNS", "NAMES", "WATER_FILLED", "schedule_from_table", "core_params", "coreflood_dp",
           "fit_coreflood", "synthetic_coreflood"]

KIND = "polymer_coreflood"
COLUMNS = {
    "pv": ("PV",),
    "dp": ("Pa", "kPa", "psi", "bar", "mbar", "atm"),
    "c_polymer_in": ("ppm", "wt%", "mg/l"),
    "salinity_in": ("ppm", "mg/l", "wt%"),
}
NAMES = ("PERM", "BRK", "CRK")
_SPEC = {s.name: s for s in PARAMETERS}
#: single-phase (water-filled) core: no oil, no residual phases, unit end-point water relative permeability
WATER_FILLED = {"SWI": 1.0, "S1RWC": 0.0, "S2RWC": 0.0, "S3RWC": 0.0, "P1RWC": 1.0}
#: output grid spacing of the simulator (PV); the lab rows must lie on it
PV_STEP = 0.05


def schedule_from_table(data: xr.Dataset) -> list[dict]:
    """Slugs (``pv``, ``salinity_ppm``, ``polymer_ppm``) from the injected-composition columns (module docstring)."""
    pv, cp, sal = data["pv"].values, data["c_polymer_in"].values, data["salinity_in"].values
    where = f"lab table {data.attrs.get('source', '?')!r}"
    if pv[0] != 0.0 or not np.all(np.diff(pv) > 0):
        raise FitError(f"{where}: column 'pv' must start at 0 and increase strictly")
    slugs, start = [], 0.0
    for i in range(1, pv.size):
        last = i == pv.size - 1
        if last or cp[i + 1] != cp[i] or sal[i + 1] != sal[i]:
            slugs.append({"pv": float(pv[i] - start), "salinity_ppm": float(sal[i]), "polymer_ppm": float(cp[i])})
            start = float(pv[i])
    return slugs


def core_params(data: xr.Dataset, fixed: Mapping[str, float]) -> dict[str, float]:
    """Forward-model parameters of the lab core: water-filled state, metadata, then the ``fixed`` overrides."""
    return {
        **WATER_FILLED,
        "LENGTH": lab_meta(data, "length", ("m", "cm", "in", "ft")),
        "DIAMETER": lab_meta(data, "diameter", ("m", "cm", "in", "ft")),
        "PORO": lab_meta(data, "porosity"),
        "QINJ": lab_meta(data, "flow_rate", ("ml/min", "cc/min", "ml/h")),
        "VIS1": lab_meta(data, "water_viscosity", ("cP", "mPa.s")),
        **dict(fixed),
    }


def coreflood_dp(theta: Mapping[str, float], schedule, params: Mapping[str, float], pv, *, cells: int) -> np.ndarray:
    """Simulated pressure drop (Pa) at the injected PVs ``pv`` (on the ``PV_STEP`` grid)."""
    ds = simulate(schedule, {**params, **theta}, cells=cells, pv_step=PV_STEP)
    return np.interp(pv, ds["pv"].values, ds["dp"].values)


def _darcy_perm_md(data, params) -> float:
    """Darcy permeability (mD) from the initial water-flood pressure, ``k = q mu L / (A dp)``: the starting value."""
    first_polymer = np.flatnonzero(data["c_polymer_in"].values > 0)
    end = first_polymer[0] if first_polymer.size else data.sizes["point"]
    dp_w = float(np.median(data["dp"].values[:max(end, 1)]))
    q = params["QINJ"] * 1e-6 / 60.0
    area = np.pi * params["DIAMETER"] ** 2 / 4.0
    return q * params["VIS1"] * 1e-3 * params["LENGTH"] / (area * dp_w) / 9.869233e-16


def fit_coreflood(data: xr.Dataset, *, fixed: Mapping[str, float] | None = None, cells: int = 30) -> xr.Dataset:
    """Fit ``PERM``, ``BRK``, ``CRK`` to a coreflood pressure history; a FIT dataset (+ data and ``dp_fit`` on
    ``point``, and the water-flood pressure ``dp_water`` attr in Pa)."""
    where = f"lab table {data.attrs.get('source', '?')!r}"
    dp = data["dp"].values
    if not np.all(dp > 0):
        raise FitError(f"{where}: column 'dp' must be > 0 everywhere (log residuals)")
    on_grid = np.abs(data["pv"].values / PV_STEP - np.round(data["pv"].values / PV_STEP)) < 1e-6
    if not on_grid.all():
        raise FitError(f"{where}: column 'pv' must lie on the {PV_STEP} PV grid of the simulator "
                       f"(first off-grid value {data['pv'].values[~on_grid][0]!r})")
    if not np.any(data["c_polymer_in"].values > 0):
        raise FitError(f"{where}: no polymer injected (column 'c_polymer_in' is 0 everywhere)")
    schedule = schedule_from_table(data)
    params = core_params(data, fixed or {})
    pv = data["pv"].values
    x0 = [_darcy_perm_md(data, params), _SPEC["BRK"].default, _SPEC["CRK"].default]
    bounds = [(_SPEC[n].lower, _SPEC[n].upper) for n in NAMES]
    x0 = [min(max(x, lo), hi) for x, (lo, hi) in zip(x0, bounds)]

    def residuals(t):
        return np.log(coreflood_dp(dict(zip(NAMES, t)), schedule, params, pv, cells=cells) / dp)

    fit = fit_least_squares(residuals, x0, names=NAMES, units=[_SPEC[n].unit for n in NAMES], bounds=bounds,
                            experiment=data.attrs.get("experiment", ""), kind=KIND)
    est = dict(zip(NAMES, fit["estimate"].values))
    for v in COLUMNS:
        fit[v] = data[v]
    fit["dp_fit"] = ("point", coreflood_dp(est, schedule, params, pv, cells=cells), {"units": "Pa"})
    fit.attrs.update(cells=cells, source=data.attrs.get("source", ""),
                     **{f"fixed_{k}": float(v) for k, v in params.items()})
    return fit


#: bundled design: initial water, three increasing polymer concentrations, water post-flush (PV, polymer ppm)
DESIGN_SLUGS = ((1.0, 0.0), (5.0, 300.0), (3.0, 1000.0), (3.0, 2500.0), (4.0, 0.0))
DESIGN_SALINITY_PPM = 9400.0
DESIGN_EVERY = 2  # one reading every DESIGN_EVERY * PV_STEP PV


def synthetic_coreflood(truth: Mapping[str, float], rng: np.random.Generator | None, *, noise: float = 0.01,
                        fixed: Mapping[str, float] | None = None, cells: int = 30) -> xr.Dataset:
    """Lab-like pressure history of the bundled design (Table 2.2 core) from the forward model with ``truth``
    (``NAMES``); multiplicative log-normal noise of relative size ``noise`` (``rng=None``: exact)."""
    defaults = {s.name: s.default for s in PARAMETERS}
    meta = {"length": f"{defaults['LENGTH']:g} m", "diameter": f"{defaults['DIAMETER']:g} m",
            "porosity": f"{defaults['PORO']:g}", "flow_rate": f"{defaults['QINJ']:g} ml/min",
            "water_viscosity": f"{defaults['VIS1']:g} cP"}
    schedule = [{"pv": pv, "salinity_ppm": DESIGN_SALINITY_PPM, "polymer_ppm": c} for pv, c in DESIGN_SLUGS]
    ends = np.cumsum([pv for pv, _ in DESIGN_SLUGS])
    pv = np.round(np.arange(0, int(round(ends[-1] / PV_STEP)) + 1, DESIGN_EVERY) * PV_STEP, 10)
    slug = np.minimum(np.searchsorted(ends, pv - 1e-9), len(DESIGN_SLUGS) - 1)
    ds = xr.Dataset({"pv": ("point", pv)}, attrs={f"meta_{k}": v for k, v in meta.items()})
    ds.attrs["source"] = "synthetic"
    params = core_params(ds, fixed or {})
    dp = coreflood_dp({n: truth[n] for n in NAMES}, schedule, params, pv, cells=cells)
    if rng is not None and noise > 0:
        dp = dp * np.exp(rng.normal(0.0, noise, dp.size))
    ds["dp"] = ("point", dp)
    ds["c_polymer_in"] = ("point", np.array([DESIGN_SLUGS[s][1] for s in slug]))
    ds["salinity_in"] = ("point", np.full(pv.size, DESIGN_SALINITY_PPM))
    for name, allowed in COLUMNS.items():
        ds[name].attrs["units"] = allowed[0]
    ds.attrs.update(kind=KIND, experiment="RRF coreflood, stepped HPAM concentrations (synthetic)",
                    meta_noise=f"{noise:g} relative (log-normal)")
    return ds
