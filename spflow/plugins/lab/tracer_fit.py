"""Dispersivity from an effluent-conductivity breakthrough curve with a linear TDS-EC relation (section 2.9).

Two lab tables: the conductivity calibration (kind ``conductivity_calibration``: columns ``tds`` in ppm and
``conductivity`` in mS/cm, Fig. 2.9a) and the effluent curve of a salinity step in a water-filled core (kind
``tracer``: columns ``pv`` and ``conductivity``; metadata ``length`` of the core and the ``initial_tds`` and
``injected_tds`` of the brines, ppm).

Model: ``TDS = A x EC`` (the thesis's linear relation, Fig. 2.9a) and the 1-D advection-dispersion solution for a step
at the inlet of a semi-infinite medium (Ogata-Banks; dispersion coefficient ``alpha_L |u|/phi``, Eq. 1.9, Peclet
number ``Pe = L / alpha_L``, no retardation for the salt), evaluated at the outlet ``x_D = 1``::

    C/C0 = 1/2 [erfc((1 - t_D) / (2 sqrt(t_D/Pe))) + exp(Pe) erfc((1 + t_D) / (2 sqrt(t_D/Pe)))]

with the second term as ``erfcx(z) exp(Pe - z^2)`` (no overflow at large Pe). Fitted jointly to both tables:
``ALPHAL1`` (ft, the forward model's aqueous dispersivity) and ``TDS_PER_EC`` (A, ppm per mS/cm), with absolute
conductivity residuals (meter error roughly constant over the 9 400-20 000 ppm range). The stated 95 % intervals are
profile-likelihood intervals (:func:`.fit_result.profile_interval`); over 2 000 synthetic seeds both they and the
linearised ones cover ALPHAL1 94.3-94.4 % and TDS_PER_EC 95.5-95.6 % (docs/lab_priors.md).
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
import xarray as xr

from spflow.plugins.forward.parameters import PARAMETERS

from .fit_result import FitError, fit_least_squares
from .lab_table import lab_meta

__all__ = ["KIND", "CALIBRATION_KIND", "COLUMNS", "CALIBRATION_COLUMNS", "NAMES", "ogata_banks_outlet",
           "effluent_conductivity", "fit_tracer", "synthetic_tracer"]

KIND = "tracer"
CALIBRATION_KIND = "conductivity_calibration"
COLUMNS = {"pv": ("PV",), "conductivity": ("mS/cm", "uS/cm", "S/m", "dS/m")}
CALIBRATION_COLUMNS = {"tds": ("ppm", "mg/l", "g/l"), "conductivity": ("mS/cm", "uS/cm", "S/m", "dS/m")}
NAMES = ("ALPHAL1", "TDS_PER_EC")
UNITS = ("ft", "ppm/(mS/cm)")
FT_TO_M = 0.3048
_ALPHA = next(s for s in PARAMETERS if s.name == "ALPHAL1")


def ogata_banks_outlet(t_d, peclet: float) -> np.ndarray:
    """Relative concentration ``C/C0`` at the outlet (``x_D = 1``) after ``t_D`` injected PV (Ogata-Banks)."""
    from scipy.special import erfc, erfcx

    t = np.asarray(t_d, dtype=float)
    out = np.zeros_like(t)
    pos = t > 0
    width = 2.0 * np.sqrt(t[pos] / peclet)
    z2 = (1.0 + t[pos]) / width
    out[pos] = 0.5 * (erfc((1.0 - t[pos]) / width) + erfcx(z2) * np.exp(peclet - z2**2))
    return out


def effluent_conductivity(pv, alpha_ft: float, tds_per_ec: float, length_m: float, tds0: float, tds_j: float):
    """Effluent conductivity (mS/cm) after ``pv`` PV for a step from ``tds0`` to ``tds_j`` ppm."""
    rel = ogata_banks_outlet(pv, length_m / (alpha_ft * FT_TO_M))
    return (tds0 + (tds_j - tds0) * rel) / tds_per_ec


def _meta(data: xr.Dataset) -> tuple[float, float, float]:
    return (lab_meta(data, "length", ("m", "cm", "in", "ft")), lab_meta(data, "initial_tds", ("ppm", "mg/l")),
            lab_meta(data, "injected_tds", ("ppm", "mg/l")))


def fit_tracer(effluent: xr.Dataset, calibration: xr.Dataset) -> xr.Dataset:
    """Joint fit of ``ALPHAL1`` and ``TDS_PER_EC``; a FIT dataset with the effluent data and fit on ``point`` and
    the calibration data and fit on ``calibration``."""
    length, tds0, tds_j = _meta(effluent)
    where = f"lab table {effluent.attrs.get('source', '?')!r}"
    if not length > 0:
        raise FitError(f"{where} metadata 'length' must be > 0")
    if tds_j == tds0:
        raise FitError(f"{where}: initial_tds and injected_tds are equal ({tds0!r} ppm): no tracer step")
    pv, ec = effluent["pv"].values, effluent["conductivity"].values
    if np.any(pv < 0):
        raise FitError(f"{where}: column 'pv' must be >= 0")
    tds_cal, ec_cal = calibration["tds"].values, calibration["conductivity"].values
    if not np.all(ec_cal > 0):
        raise FitError(f"lab table {calibration.attrs.get('source', '?')!r}: column 'conductivity' must be > 0")
    scale = float(np.mean(np.abs(ec)))
    slope0 = float(np.sum(tds_cal * ec_cal) / np.sum(ec_cal**2))  # least-squares TDS = A EC through the origin

    def residuals(t):
        model = effluent_conductivity(pv, t[0], t[1], length, tds0, tds_j)
        return np.concatenate([model - ec, tds_cal / t[1] - ec_cal]) / scale

    fit = fit_least_squares(residuals, [_ALPHA.default, slope0], names=NAMES, units=UNITS,
                            bounds=[(1e-6, _ALPHA.upper), (1e-9, None)],
                            experiment=effluent.attrs.get("experiment", ""), kind=KIND, profile=True)
    alpha, slope = fit["estimate"].values
    fit["pv"] = effluent["pv"]
    fit["conductivity"] = effluent["conductivity"]
    fit["conductivity_fit"] = ("point", effluent_conductivity(pv, alpha, slope, length, tds0, tds_j),
                               {"units": "mS/cm"})
    fit["calibration_tds"] = ("calibration", tds_cal, {"units": "ppm"})
    fit["calibration_conductivity"] = ("calibration", ec_cal, {"units": "mS/cm"})
    fit.attrs.update(length_m=length, initial_tds_ppm=tds0, injected_tds_ppm=tds_j, peclet=length / (alpha * FT_TO_M),
                     source=effluent.attrs.get("source", ""), calibration_source=calibration.attrs.get("source", ""))
    return fit


#: bundled design: IWF -> HTDS step of Table 2.5 brines, effluent every 0.02 PV up to 2.5 PV; calibration brines
DESIGN_TDS = (9400.0, 17500.0)
DESIGN_PV = tuple(np.round(np.arange(0.0, 2.5 + 1e-9, 0.02), 10).tolist())
DESIGN_CALIBRATION_TDS = (9400.0, 12000.0, 15000.0, 17500.0, 20000.0)


def synthetic_tracer(truth: Mapping[str, float], rng: np.random.Generator | None, *, noise: float = 0.01,
                     length_m: float = 0.1524) -> tuple[xr.Dataset, xr.Dataset]:
    """(effluent, calibration) lab tables of the bundled design from ``truth`` (``NAMES``); additive Gaussian noise
    of ``noise`` times the mean conductivity of the two brines (``rng=None``: exact)."""
    alpha, slope = truth["ALPHAL1"], truth["TDS_PER_EC"]
    pv = np.array(DESIGN_PV)
    ec = effluent_conductivity(pv, alpha, slope, length_m, *DESIGN_TDS)
    tds_cal = np.array(DESIGN_CALIBRATION_TDS)
    ec_cal = tds_cal / slope
    if rng is not None and noise > 0:
        sd = noise * np.mean(DESIGN_TDS) / slope
        ec = ec + rng.normal(0.0, sd, ec.size)
        ec_cal = ec_cal + rng.normal(0.0, sd, ec_cal.size)
    effluent = xr.Dataset({"pv": ("point", pv, {"units": "PV"}), "conductivity": ("point", ec, {"units": "mS/cm"})})
    effluent.attrs.update(kind=KIND, experiment="IWF -> HTDS salinity step, effluent conductivity (synthetic)",
                          meta_length=f"{length_m:g} m", meta_initial_tds=f"{DESIGN_TDS[0]:g} ppm",
                          meta_injected_tds=f"{DESIGN_TDS[1]:g} ppm", meta_noise=f"{noise:g} x mean EC (additive)")
    calibration = xr.Dataset({"tds": ("point", tds_cal, {"units": "ppm"}),
                              "conductivity": ("point", ec_cal, {"units": "mS/cm"})})
    calibration.attrs.update(kind=CALIBRATION_KIND, experiment="TDS-EC calibration brines (synthetic)",
                             meta_noise=f"{noise:g} x mean EC (additive)")
    return effluent, calibration
