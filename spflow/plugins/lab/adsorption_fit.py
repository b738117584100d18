"""Langmuir adsorption fit from static retention tests (thesis Eqs. 2.15-2.16, section 2.10).

Lab table (kind ``polymer_adsorption`` or ``surfactant_adsorption``): one row per batch test with columns
``concentration`` (equilibrium concentration of the solution; polymer in wt %, surfactant as volume fraction; ppm
accepted), ``salinity`` (TDS of the brine, ppm) and ``adsorbed`` (retained mass per rock mass, mg/g); metadata
``rock_density`` (g/cm3) and ``porosity`` of the rock the isotherm is for.

Conversion to UTCHEM pore-volume units (solution density 1 g/ml, the forward model's own convention for ppm):
``C_hat = Gamma rho_r (1 - phi) / phi`` as a mass fraction of the pore volume, i.e. x100 for wt % (polymer), x1 for
the volume fraction (surfactant). Model: the forward kernels ``C_hat = C a / (1 + b C)`` with
``a = a1 + a2 C_SE`` (Eq. 2.16 without the permeability factor: static tests are on the rock itself), ``C_SE`` the
effective salinity the simulator would compute for that brine (``C_SEP`` with BETAP for polymer, ``C_SE`` with
BETA6 f6 for surfactant). Fitted ``AD41, AD42, B4D`` (polymer) or ``AD31, AD32, B3D`` (surfactant), with absolute
residuals scaled by the largest retention (batch-test error is roughly constant in mg/g). The stated 95 % intervals
are profile-likelihood intervals (:func:`.fit_result.profile_interval`), which stay inside the bounds: a salinity
slope estimated at its bound 0 (Table 2.4 truth) gets ``[0, upper]``.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
import xarray as xr

from spflow.plugins.forward import units
from spflow.plugins.forward.parameters import PARAMETERS

from .fit_result import FitError, fit_least_squares
from .lab_table import lab_meta

__all__ = ["COMPONENTS", "columns", "effective_salinity", "isotherm", "fit_adsorption", "synthetic_adsorption"]

_SPEC = {s.name: s for s in PARAMETERS}
#: component -> (lab-table kind, parameter names, canonical concentration unit, PV-unit factor from mass fraction)
COMPONENTS = {
    "polymer": ("polymer_adsorption", ("AD41", "AD42", "B4D"), "wt%", 100.0),
    "surfactant": ("surfactant_adsorption", ("AD31", "AD32", "B3D"), "vol.frac.", 1.0),
}


def _component(component: str):
    if component not in COMPONENTS:
        raise FitError(f"component {component!r} is not allowed; allowed: {', '.join(COMPONENTS)}")
    return COMPONENTS[component]


def columns(component: str) -> dict[str, tuple[str, ...]]:
    """Lab-table columns of the ``component``'s adsorption test (canonical unit first)."""
    conc = _component(component)[2]
    return {"concentration": (conc, "ppm", "mg/l"), "salinity": ("ppm", "mg/l"), "adsorbed": ("mg/g", "ug/g")}


def effective_salinity(component: str, tds_ppm, fixed: Mapping[str, float] | None = None) -> np.ndarray:
    """Effective salinity (meq/ml) the simulator sees for a brine of ``tds_ppm`` (forward-model TDS conversion)."""
    from spflow.plugins.forward.physics.effective_salinity import (
        phase_behaviour_effective_salinity,
        polymer_effective_salinity,
    )

    p = {s.name: s.default for s in PARAMETERS} | dict(fixed or {})
    tds = np.asarray(tds_ppm, dtype=float)
    c51, c61 = units.tds_ppm_to_anions(tds), units.tds_ppm_to_divalent(tds)
    if _component(component)[0] == "polymer_adsorption":
        return polymer_effective_salinity(c51, c61, 1.0, p["BETAP"])
    return phase_behaviour_effective_salinity(c51, p["BETA6"], p["F6S"])


def isotherm(conc, cse, a1: float, a2: float, b: float) -> np.ndarray:
    """Adsorbed concentration (PV units) ``C a/(1 + b C)``, ``a = a1 + a2 C_SE`` (Eqs. 2.15-2.16)."""
    from .lab_kernels import isotherm_loop  # numba: compiled on first use, not when the stage is declared

    c, s = np.broadcast_arrays(np.asarray(conc, dtype=float), np.asarray(cse, dtype=float))
    return isotherm_loop(np.ascontiguousarray(c.ravel()), np.ascontiguousarray(s.ravel()),
                         float(a1), float(a2), float(b)).reshape(c.shape)


def _pv_factor(data: xr.Dataset, component: str) -> float:
    """mg/g of rock -> adsorbed concentration per pore volume (wt % or volume fraction)."""
    rho = lab_meta(data, "rock_density", ("g/cm3", "g/ml", "kg/m3"))
    phi = lab_meta(data, "porosity")
    if not 0.0 < phi < 1.0:
        raise FitError(f"lab table {data.attrs.get('source', '?')!r} metadata 'porosity' = {phi!r} must be in (0, 1)")
    if not rho > 0.0:
        raise FitError(f"lab table {data.attrs.get('source', '?')!r} metadata 'rock_density' must be > 0")
    return 1e-3 * rho * (1.0 - phi) / phi * _component(component)[3]


def fit_adsorption(data: xr.Dataset, component: str, *, fixed: Mapping[str, float] | None = None) -> xr.Dataset:
    """Fit the Langmuir parameters of ``component`` to a static retention table; a FIT dataset (+ data,
    ``c_hat`` data and fit in PV units and ``cse`` on ``point``)."""
    kind, names, conc_unit, _ = _component(component)
    conc, ads = data["concentration"].values, data["adsorbed"].values
    where = f"lab table {data.attrs.get('source', '?')!r}"
    if not np.all(conc > 0):
        raise FitError(f"{where}: column 'concentration' must be > 0 everywhere")
    c_hat = ads * _pv_factor(data, component)
    cse = effective_salinity(component, data["salinity"].values, fixed)
    scale = float(np.max(np.abs(c_hat))) or 1.0
    # starting values: Langmuir linearisation C / C_hat = 1/a + (b/a) C at the mean salinity
    good = c_hat > 0
    if good.sum() < 2:
        raise FitError(f"{where}: at least two positive retention values are needed")
    slope, intercept = np.polyfit(conc[good], conc[good] / c_hat[good], 1)
    a_start = 1.0 / intercept if intercept > 0 else scale / float(np.median(conc))
    b_start = slope * a_start if slope > 0 else 1.0 / float(np.median(conc))
    bounds = [(_SPEC[n].lower, _SPEC[n].upper) for n in names]
    x0 = [min(max(x, lo), hi) for x, (lo, hi) in zip((a_start, 0.0, b_start), bounds)]

    def residuals(t):
        return (isotherm(conc, cse, *t) - c_hat) / scale

    fit = fit_least_squares(residuals, x0, names=names, units=[_SPEC[n].unit for n in names], bounds=bounds,
                            experiment=data.attrs.get("experiment", ""), kind=kind, profile=True)
    for v in ("concentration", "salinity", "adsorbed"):
        fit[v] = data[v]
    fit["c_hat"] = ("point", c_hat, {"units": conc_unit})
    fit["c_hat_fit"] = ("point", isotherm(conc, cse, *fit["estimate"].values), {"units": conc_unit})
    fit["cse"] = ("point", cse, {"units": "meq/ml"})
    fit.attrs.update(component=component, pv_factor=_pv_factor(data, component),
                     source=data.attrs.get("source", ""))
    return fit


#: bundled designs: equilibrium concentrations (ppm) and brines (TDS ppm) of the batch tests
DESIGN = {
    "polymer": ((25, 50, 100, 200, 400, 800, 1500, 3000), (9400.0, 22000.0)),
    "surfactant": ((500, 1000, 2000, 4000, 7000, 10000, 15000, 20000, 30000), (9400.0, 22000.0)),
}
ROCK_DENSITY_G_CM3 = 2.65


def synthetic_adsorption(component: str, truth: Mapping[str, float], rng: np.random.Generator | None, *,
                         noise: float = 0.04) -> xr.Dataset:
    """Lab-like static retention data of the bundled design from ``truth`` (the component's three names).

    Additive Gaussian noise of standard deviation ``noise`` times the Langmuir plateau ``(a1 + a2 C_SE,max)/b``
    in mg/g (``rng=None``: exact). Rock: Table 2.3 Berea porosity, density 2.65 g/cm3.
    """
    kind, names, conc_unit, _ = _component(component)
    ppm, brines = DESIGN[component]
    c_ppm, tds = (np.array(v, dtype=float) for v in zip(*[(c, s) for s in brines for c in ppm]))
    conc = c_ppm * 1e-4 if conc_unit == "wt%" else c_ppm * 1e-6
    ds = xr.Dataset(attrs={"source": "synthetic", "meta_rock_density": f"{ROCK_DENSITY_G_CM3:g} g/cm3",
                           "meta_porosity": f"{_SPEC['PORO'].default:g}"})
    factor = _pv_factor(ds, component)
    cse = effective_salinity(component, tds)
    gamma = isotherm(conc, cse, *(truth[n] for n in names)) / factor
    if rng is not None and noise > 0:
        plateau = (truth[names[0]] + truth[names[1]] * cse.max()) / truth[names[2]] / factor
        gamma = gamma + rng.normal(0.0, noise * plateau, gamma.size)
    ds["concentration"] = ("point", conc, {"units": conc_unit})
    ds["salinity"] = ("point", tds, {"units": "ppm"})
    ds["adsorbed"] = ("point", gamma, {"units": "mg/g"})
    ds.attrs.update(kind=kind, experiment=f"static {component} retention on crushed Berea (synthetic)",
                    meta_noise=f"{noise:g} x plateau (additive Gaussian)")
    return ds
