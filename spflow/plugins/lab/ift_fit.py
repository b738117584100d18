"""Interfacial tension vs solubilization ratio fitted with the modified Chun-Huh law: CHUH (c), AHUH (a) (thesis
section 2.6, Eqs. 2.9-2.10, Fig. 2.6).

Each measurement is the IFT between the microemulsion (ME) and one excess phase, ``interface`` 1 (water/ME,
``sigma13`` against ``R13``) or 2 (oil/ME, ``sigma23`` against ``R23``), with both solubilization ratios of the ME
read from the same tube. The fitted model is the forward simulator's kernel
:func:`spflow.plugins.forward.physics.ift.chun_huh_ift`
``sigma_l3 = sigma_ow exp(-a R_l3) + (c F_l / R_l3^2)(1 - exp(-a R_l3^3))`` with Hirasaki's factor ``F_l``
(:func:`~spflow.plugins.forward.physics.ift.hirasaki_factor`, Eq. 2.10) between the pure excess phase and the ME
composition ``(R13, R23, 1) / (1 + R13 + R23)`` -- exactly how the simulator evaluates it. ``sigma_ow = 10^XIFTW``
(mN/m) is measured separately and read from the table's metadata ``xiftw``.

Spinning-drop IFTs span decades with a roughly constant relative error: residuals ``log sigma_model - log
sigma_data`` with a common, estimated noise level. ``a`` is identified only by tubes with ``R`` of order
``a^(-1/3)`` or less (dilute surfactant), where the oil-water term still shows through; large-``R`` tubes fix ``c``.
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from spflow.plugins.forward.parameters import PARAMETERS
from spflow.plugins.lab.fit_result import FitError, fit_least_squares
from spflow.plugins.lab.lab_table import lab_meta, read_lab_table
from spflow.plugins.lab.phase_behaviour_fit import overall_composition

__all__ = ["KIND", "COLUMNS", "NAMES", "ift_model", "read_ift_table", "synthetic_ift_table", "fit_ift"]

KIND = "ift"
_RATIO_UNITS = ("-", "1", "fraction")
#: required columns -> allowed units (canonical first)
COLUMNS = {"interface": ("-", "1"), "r_water": _RATIO_UNITS, "r_oil": _RATIO_UNITS,
           "ift": ("mN/m", "dyn/cm", "dyne/cm", "N/m")}
#: fitted forward-model parameters (c, a of Eq. 2.9)
NAMES = ("CHUH", "AHUH")
_SPEC = {p.name: p for p in PARAMETERS}


def ift_model(interface, r_water, r_oil, chuh: float, ahuh: float, sigma_ow: float) -> np.ndarray:
    """IFT (mN/m) between the ME of ratios ``(r_water, r_oil)`` and pure excess water (``interface`` 1) or pure
    excess oil (``interface`` 2), Eqs. 2.9-2.10 via the forward model's kernels."""
    from spflow.plugins.forward.physics.ift import chun_huh_ift, hirasaki_factor

    interface = np.asarray(interface)
    r13 = np.asarray(r_water, dtype=float)
    r23 = np.asarray(r_oil, dtype=float)
    out = np.empty(r13.shape)
    for i in np.ndindex(out.shape):
        c33 = 1.0 / (1.0 + r13[i] + r23[i])
        c13, c23 = r13[i] * c33, r23[i] * c33
        if interface[i] == 1:
            f = hirasaki_factor(1.0, 0.0, 0.0, c13, c23, c33)
            out[i] = chun_huh_ift(r13[i], f, sigma_ow, chuh, ahuh)
        else:
            f = hirasaki_factor(0.0, 1.0, 0.0, c13, c23, c33)
            out[i] = chun_huh_ift(r23[i], f, sigma_ow, chuh, ahuh)
    return out


def _check(ds: xr.Dataset, where: str) -> float:
    """Validate the columns' values and return ``sigma_ow`` (mN/m) from the metadata ``xiftw``."""
    xiftw = lab_meta(ds, "xiftw")
    spec = _SPEC["XIFTW"]
    if not spec.lower <= xiftw <= spec.upper:
        raise FitError(f"{where}: xiftw = {xiftw!r} outside the allowed range {spec.describe_range()}")
    interface = ds["interface"].values
    bad = ~np.isin(interface, (1.0, 2.0))
    if bad.any():
        raise FitError(f"{where}: column 'interface' must be 1 (water/ME) or 2 (oil/ME); data row "
                       f"{int(np.argmax(bad)) + 1} has {float(interface[bad][0]):g}")
    for col in ("r_water", "r_oil", "ift"):
        values = ds[col].values
        low = values <= 0.0 if col == "ift" else values < 0.0
        if low.any():
            raise FitError(f"{where}: column {col!r} must be {'> 0' if col == 'ift' else '>= 0'}; data row "
                           f"{int(np.argmax(low)) + 1} has {float(values[low][0]):g}")
    return 10.0**xiftw


def read_ift_table(path) -> xr.Dataset:
    """Read an ``ift`` lab table (columns interface, r_water, r_oil, ift; bare-number metadata ``xiftw``)."""
    ds = read_lab_table(path, KIND, COLUMNS)
    _check(ds, f"lab table {str(path)!r}")
    return ds


def synthetic_ift_table(truth: dict[str, float], salinity, surfactant, *, water_oil_ratio: float = 1.0,
                        noise: float = 0.08, seed: int = 0, experiment: str = "synthetic IFT scan") -> xr.Dataset:
    """Lab-like IFTs of every tube of a salinity x surfactant-concentration scan.

    Each tube (overall surfactant fraction ``surfactant[j]`` at ``salinity[i]``) is flashed with the truth's phase
    behaviour (the forward model's :func:`~spflow.plugins.forward.physics.phase_behaviour.flash`); for each excess
    phase present beside the ME the Chun-Huh IFT with the truth's CHUH/AHUH/XIFTW is recorded times
    ``exp(N(0, noise^2))``.
    """
    from spflow.plugins.forward.physics.phase_behaviour import flash, solubilization_ratios

    theta = [truth[n] for n in ("CSEL", "CSEU", "HBNC70", "HBNC71", "HBNC72")]
    rows = []
    for z3 in np.atleast_1d(surfactant):
        z = overall_composition(float(z3), water_oil_ratio)
        for s in np.asarray(salinity, dtype=float):
            _, s1, s2, s3, *_, c13, c23, c33 = flash(*z, float(s), *theta, truth["EPSME"])
            if not (s3 > 0.0 and c33 > 0.0):
                continue
            r13, r23 = solubilization_ratios(c13, c23, c33)
            rows.extend((interface, r13, r23) for interface, present in ((1, s1), (2, s2)) if present > 0.0)
    if len(rows) < 3:
        raise FitError("synthetic_ift_table: fewer than 3 tubes with a microemulsion beside an excess phase")
    interface, r_water, r_oil = (np.array(c, dtype=float) for c in zip(*rows))
    sigma = ift_model(interface, r_water, r_oil, truth["CHUH"], truth["AHUH"], 10.0 ** truth["XIFTW"])
    sigma *= np.exp(noise * np.random.default_rng(seed).standard_normal(sigma.size))
    return xr.Dataset(
        {
            "interface": ("point", interface, {"units": "-", "long_name": "1 water/ME, 2 oil/ME"}),
            "r_water": ("point", r_water, {"units": "-"}),
            "r_oil": ("point", r_oil, {"units": "-"}),
            "ift": ("point", sigma, {"units": "mN/m"}),
        },
        attrs={"kind": KIND, "experiment": experiment, "meta_xiftw": f"{truth['XIFTW']:g}"},
    )


def _start(ratio, sigma, f) -> list[float]:
    """Data-driven start: ``c`` from the large-ratio tail (``sigma ~ c F / R^2``), ``a`` at the low end of UTCHEM's
    typical range (5; UTCHEM-9.0 User's Guide: 5-20)."""
    tail = ratio >= np.quantile(ratio, 0.5)
    c0 = float(np.median(sigma[tail] * ratio[tail] ** 2 / np.maximum(f[tail], 1e-3)))
    spec = _SPEC["CHUH"]
    return [min(max(c0, spec.lower), spec.upper), 5.0]


def fit_ift(data: xr.Dataset, *, curve_points: int = 200) -> xr.Dataset:
    """Fit (CHUH, AHUH) to an IFT table read by :func:`read_ift_table`.

    Returns the FIT dataset plus the data (``interface``, ``ratio`` = the ratio of the measured interface, ``ift``
    on dim ``point``) and the fitted law with ``F = 1`` (``curve_ift`` on dim ``curve_ratio``, log-spaced over the
    measured ratios) for the figure.
    """
    from spflow.plugins.forward.physics.ift import chun_huh_ift, hirasaki_factor

    where = f"IFT table {data.attrs.get('source', '')!r}"
    sigma_ow = _check(data, where)
    interface = data["interface"].values
    r13, r23 = data["r_water"].values, data["r_oil"].values
    ratio = np.where(interface == 1, r13, r23)
    if np.unique(ratio).size < 3:
        raise FitError(f"{where}: need at least 3 distinct solubilization ratios")
    log_data = np.log(data["ift"].values)

    def residuals(theta):
        return np.log(ift_model(interface, r13, r23, theta[0], theta[1], sigma_ow)) - log_data

    c33 = 1.0 / (1.0 + r13 + r23)
    f = np.array([hirasaki_factor(float(i == 1), float(i == 2), 0.0, a * c, b * c, c)
                  for i, a, b, c in zip(interface, r13, r23, c33)])
    x0 = _start(ratio, data["ift"].values, f)
    fit = fit_least_squares(residuals, x0, names=NAMES, units=[_SPEC[n].unit for n in NAMES],
                            bounds=[(_SPEC[n].lower, _SPEC[n].upper) for n in NAMES],
                            experiment=data.attrs.get("experiment", ""), kind=KIND)
    positive = ratio[ratio > 0.0]
    grid = np.geomspace(positive.min(), positive.max(), curve_points)
    chuh, ahuh = fit["estimate"].values
    curve = np.array([chun_huh_ift(r, 1.0, sigma_ow, chuh, ahuh) for r in grid])
    fit["interface"] = ("point", interface.astype(int),
                        {"units": "1", "long_name": "excess phase of the measurement: 1 water/ME, 2 oil/ME"})
    fit["ratio"] = ("point", ratio, {"units": "-", "long_name": "R13 (water/ME) or R23 (oil/ME)"})
    fit["ift"] = ("point", data["ift"].values, {"units": "mN/m"})
    fit = fit.assign_coords(curve_ratio=("curve_ratio", grid, {"units": "-"}))
    fit["curve_ift"] = ("curve_ratio", curve, {"units": "mN/m", "long_name": "Eq. 2.9 with F = 1"})
    fit.attrs.update(sigma_ow=sigma_ow, residuals="log(sigma_model) - log(sigma_data)")
    return fit
