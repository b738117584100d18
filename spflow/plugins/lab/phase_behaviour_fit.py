"""Pipette (salinity-scan) tests fitted with Hand's rule: CSEL, CSEU, HBNC70-72 (thesis section 2.5, Fig. 2.5).

A pipette test mixes brine of salinity ``C_SE`` (meq/ml), oil and surfactant at a known overall surfactant volume
fraction ``z3`` and water/oil ratio, lets it equilibrate and reads the microemulsion (ME) volume fractions: the
solubilization ratios ``R13 = V_w/V_s`` (water in the ME per volume of surfactant) and ``R23 = V_o/V_s``.

The fitted model is the forward simulator's own flash
(:func:`spflow.plugins.forward.physics.phase_behaviour.flash`, Hand's rule with the salinity interpolation of the
binodal heights, :func:`~spflow.plugins.forward.physics.phase_behaviour.hand_a_salinity`) followed by
:func:`~spflow.plugins.forward.physics.phase_behaviour.solubilization_ratios`: for every tube the overall composition
is flashed at the tube's salinity and the ME's ratios are compared with the readings. In the Winsor I (type II(-))
tubes all the water is in the ME (``R13 = z1/z3``) and ``R23 = z3/(A z1)`` measures the binodal height through
``A``; in type III the invariant point gives ``R13 = (1 - w)/q``, ``R23 = w/q`` with
``w = (C_SE - CSEL)/(CSEU - CSEL)``; Winsor II (type II(+)) mirrors type II(-).

Pipette readings are volume readings of a small ME volume per small surfactant volume, so the error is
multiplicative: the residuals are ``log R_model - log R_data`` with a common, estimated noise level.
Non-positive or empty readings are not fitted (an empty cell = the ratio was not read in that tube).
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from spflow.plugins.forward.parameters import PARAMETERS
from spflow.plugins.lab.fit_result import FitError, fit_least_squares
from spflow.plugins.lab.lab_table import lab_meta, read_lab_table

__all__ = ["KIND", "COLUMNS", "NAMES", "overall_composition", "solubilization_curve", "read_pipette_tests",
           "synthetic_pipette_tests", "fit_phase_behaviour"]

KIND = "phase_behaviour"
_RATIO_UNITS = ("-", "1", "fraction")
#: required columns -> allowed units (canonical first)
COLUMNS = {"salinity": ("meq/ml", "eq/l", "meq/l"), "r_water": _RATIO_UNITS, "r_oil": _RATIO_UNITS}
#: fitted forward-model parameters (HBNC70/71/72 = C33max0/1/2 of the thesis)
NAMES = ("CSEL", "CSEU", "HBNC70", "HBNC71", "HBNC72")
_SPEC = {p.name: p for p in PARAMETERS}
#: model ratios are kept in this range before the logarithm (a binodal of zero height, possible only when Hand's A
#: is extrapolated beyond twice the optimal salinity with HBNC72 < HBNC71, would give an infinite ratio)
_RATIO_RANGE = (1e-6, 1e6)


def overall_composition(surfactant: float, water_oil_ratio: float) -> tuple[float, float, float]:
    """Overall volume fractions ``(z1, z2, z3)`` of a tube from its surfactant fraction and brine/oil ratio."""
    z1 = (1.0 - surfactant) * water_oil_ratio / (1.0 + water_oil_ratio)
    return z1, 1.0 - surfactant - z1, surfactant


def solubilization_curve(salinity, theta, *, surfactant: float, water_oil_ratio: float = 1.0,
                         epsme: float = _SPEC["EPSME"].default) -> tuple[np.ndarray, np.ndarray]:
    """Solubilization ratios ``(R13, R23)`` of the ME in pipettes at ``salinity`` (meq/ml).

    ``theta`` = (CSEL, CSEU, HBNC70, HBNC71, HBNC72); ``surfactant`` the overall surfactant volume fraction of a tube,
    ``water_oil_ratio`` its brine/oil volume ratio; ``epsme`` the CMC. Tubes without an ME give ``(0, 0)``.
    """
    from spflow.plugins.forward.physics.phase_behaviour import flash, solubilization_ratios

    csel, cseu, c0, c1, c2 = (float(x) for x in theta)
    z1, z2, z3 = overall_composition(surfactant, water_oil_ratio)
    cse = np.asarray(salinity, dtype=float)
    r13 = np.empty(cse.shape)
    r23 = np.empty(cse.shape)
    for i, s in np.ndenumerate(cse):
        out = flash(z1, z2, z3, float(s), csel, cseu, c0, c1, c2, epsme)
        r13[i], r23[i] = solubilization_ratios(out[10], out[11], out[12])
    return r13, r23


def _check_setup(surfactant: float, water_oil_ratio: float, where: str) -> None:
    if not 0.0 < surfactant < 1.0:
        raise FitError(f"{where}: surfactant volume fraction {surfactant!r} must be in (0, 1)")
    if not water_oil_ratio > 0.0:
        raise FitError(f"{where}: water_oil_ratio {water_oil_ratio!r} must be > 0")


def read_pipette_tests(path) -> xr.Dataset:
    """Read a ``phase_behaviour`` lab table (columns salinity, r_water, r_oil; metadata ``surfactant`` with a
    fraction/% unit and bare ``water_oil_ratio``); empty ratio cells are allowed (not read in that tube)."""
    ds = read_lab_table(path, KIND, COLUMNS, allow_empty=("r_water", "r_oil"))
    surfactant = lab_meta(ds, "surfactant", ("fraction", "%", "vol%"))
    wor = lab_meta(ds, "water_oil_ratio")
    _check_setup(surfactant, wor, f"lab table {str(path)!r}")
    return ds


def synthetic_pipette_tests(truth: dict[str, float], salinity, *, surfactant: float = 0.00678,
                            water_oil_ratio: float = 1.0, noise: float = 0.05, seed: int = 0,
                            experiment: str = "synthetic pipette tests") -> xr.Dataset:
    """Lab-like pipette readings: the model ratios times ``exp(N(0, noise^2))`` (``noise`` = log-sd, i.e. about
    ``100 noise`` % reading error), laid out like :func:`read_pipette_tests` returns them."""
    theta = [truth[n] for n in NAMES]
    r13, r23 = solubilization_curve(salinity, theta, surfactant=surfactant, water_oil_ratio=water_oil_ratio)
    rng = np.random.default_rng(seed)
    factor = np.exp(noise * rng.standard_normal((2, r13.size)))
    ds = xr.Dataset(
        {
            "salinity": ("point", np.asarray(salinity, dtype=float), {"units": "meq/ml"}),
            "r_water": ("point", r13 * factor[0], {"units": "-"}),
            "r_oil": ("point", r23 * factor[1], {"units": "-"}),
        },
        attrs={"kind": KIND, "experiment": experiment, "meta_surfactant": f"{surfactant:.6g} fraction",
               "meta_water_oil_ratio": f"{water_oil_ratio:g}"},
    )
    return ds


def _start(salinity, r13, r23, z1, z2, z3) -> np.ndarray:
    """Starting values from the readings: the optimal salinity where the ratios cross, ``HBNC71`` from the ratio
    there (``R = (1 - C)/(2 C)``), ``HBNC70``/``HBNC72`` from the end tubes' Hand's A extrapolated linearly in
    salinity (falling back to ``HBNC71``)."""
    order = np.argsort(salinity)
    s, lw, lo = salinity[order], np.log(r13[order]), np.log(r23[order])
    gap = lw - lo
    cross = np.nonzero((gap[:-1] > 0) & (gap[1:] <= 0))[0]
    if cross.size == 0:
        raise FitError(f"pipette tests: the water and oil solubilization ratios never cross over salinities "
                       f"[{s[0]:g}, {s[-1]:g}] meq/ml, so the optimal salinity (CSEL, CSEU) is not bracketed")
    k = cross[0]
    t = gap[k] / (gap[k] - gap[k + 1])
    s_opt = s[k] + t * (s[k + 1] - s[k])
    r_opt = np.exp(0.5 * ((1 - t) * (lw[k] + lo[k]) + t * (lw[k + 1] + lo[k + 1])))
    c1 = 1.0 / (2.0 * r_opt + 1.0)
    a1 = (2.0 * c1 / (1.0 - c1)) ** 2

    def height(a_end, frac):
        a = (a_end - a1 * (1.0 - frac)) / frac if frac > 0.0 else a_end
        if not a > 0.0:
            return c1
        return np.sqrt(a) / (2.0 + np.sqrt(a))

    c0 = height(z3 / (r23[order][0] * z1), 1.0 - s[0] / s_opt)
    c2 = height(z3 / (r13[order][-1] * z2), s[-1] / s_opt - 1.0)
    x0 = np.array([0.9 * s_opt, 1.1 * s_opt, c0, c1, c2])
    lo_b = np.array([_SPEC[n].lower for n in NAMES])
    hi_b = np.array([_SPEC[n].upper for n in NAMES])
    return np.clip(x0, lo_b, hi_b)


def fit_phase_behaviour(data: xr.Dataset, *, curve_points: int = 200) -> xr.Dataset:
    """Fit (CSEL, CSEU, HBNC70, HBNC71, HBNC72) to pipette tests read by :func:`read_pipette_tests`.

    Returns the FIT dataset of :func:`spflow.plugins.lab.fit_result.fit_least_squares` plus the readings
    (``salinity``, ``r_water``, ``r_oil`` on dim ``point``) and the fitted curves (``curve_r_water``,
    ``curve_r_oil`` on dim ``curve_salinity``, ``curve_points`` salinities spanning the tubes).
    """
    surfactant = lab_meta(data, "surfactant", ("fraction", "%", "vol%"))
    wor = lab_meta(data, "water_oil_ratio")
    _check_setup(surfactant, wor, f"pipette tests {data.attrs.get('source', '')!r}")
    z1, z2, z3 = overall_composition(surfactant, wor)
    sal = np.asarray(data["salinity"].values, dtype=float)
    r13 = np.asarray(data["r_water"].values, dtype=float)
    r23 = np.asarray(data["r_oil"].values, dtype=float)
    if np.any(sal < 0.0):
        raise FitError(f"pipette tests: salinity must be >= 0 meq/ml, got min {sal.min():g}")
    use13 = np.isfinite(r13) & (r13 > 0.0)
    use23 = np.isfinite(r23) & (r23 > 0.0)
    both = use13 & use23
    if both.sum() < 2:
        raise FitError("pipette tests: at least two tubes need both solubilization ratios read")
    x0 = _start(sal[both], r13[both], r23[both], z1, z2, z3)
    log13, log23 = np.log(r13[use13]), np.log(r23[use23])

    def residuals(theta):
        m13, m23 = solubilization_curve(sal, theta, surfactant=surfactant, water_oil_ratio=wor)
        m13 = np.clip(m13, *_RATIO_RANGE)
        m23 = np.clip(m23, *_RATIO_RANGE)
        return np.concatenate([np.log(m13[use13]) - log13, np.log(m23[use23]) - log23])

    fit = fit_least_squares(residuals, x0, names=NAMES, units=[_SPEC[n].unit for n in NAMES],
                            bounds=[(_SPEC[n].lower, _SPEC[n].upper) for n in NAMES],
                            experiment=data.attrs.get("experiment", ""), kind=KIND)
    grid = np.linspace(sal.min(), sal.max(), curve_points)
    c13, c23 = solubilization_curve(grid, fit["estimate"].values, surfactant=surfactant, water_oil_ratio=wor)
    fit["salinity"] = ("point", sal, {"units": "meq/ml"})
    fit["r_water"] = ("point", r13, {"units": "-", "long_name": "V_w/V_s read"})
    fit["r_oil"] = ("point", r23, {"units": "-", "long_name": "V_o/V_s read"})
    fit = fit.assign_coords(curve_salinity=("curve_salinity", grid, {"units": "meq/ml"}))
    fit["curve_r_water"] = ("curve_salinity", c13, {"units": "-"})
    fit["curve_r_oil"] = ("curve_salinity", c23, {"units": "-"})
    fit.attrs.update(surfactant=surfactant, water_oil_ratio=wor, residuals="log(R_model) - log(R_read)")
    return fit
