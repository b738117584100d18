"""Assemble the kernel's arrays into the public ``xarray.Dataset`` (names, units, sampling conventions)."""

from __future__ import annotations

import numpy as np
import xarray as xr

from . import kernel as KR
from . import output_records as R
from . import units

__all__ = ["build_dataset", "COMPONENTS", "PROFILE_VARIABLES"]

#: component order of the kernel's mass-balance totals
COMPONENTS = ("water", "oil", "surfactant", "polymer", "anions", "divalent")

_AVG = "average over the pv interval (previous grid point, pv]; at pv = 0 the initial outlet value"
_POINT = "point value at pv"

_SERIES = (
    ("dp", R.DP, "Pa", "pressure drop |P_inj - P_prod| (of the global pressure when Pc is on)", _POINT, 1.0),
    ("oil_cut", R.OIL_CUT, "1", "oil cut (oil volume fraction of the effluent)", _AVG, 1.0),
    ("recovery", R.RECOVERY, "1", "cumulative oil recovery, fraction of OOIP (0 if OOIP = 0)", _POINT, 1.0),
    ("c_polymer_out", R.CP_OUT, "ppm", "effluent polymer concentration in the polymer-carrying phase", _AVG,
     units.wt_percent_to_polymer_ppm(1.0)),
    ("c_surfactant_out", R.CS_OUT, "ppm", "effluent surfactant concentration (overall, by volume)", _AVG,
     units.volume_fraction_to_surfactant_ppm(1.0)),
    ("salinity_out", R.SAL_OUT, "ppm", "effluent salinity (TDS) of the produced water", _AVG,
     units.anions_to_tds_ppm(1.0)),
)

#: ``(name, row of the kernel's profile array, units, long_name, scale)`` of every profile variable (1-D and 2-D)
PROFILE_VARIABLES = (
    ("sw", KR.P_SW, "1", "aqueous-phase (water) saturation", 1.0),
    ("so", KR.P_SO, "1", "oleic-phase saturation", 1.0),
    ("sme", KR.P_SME, "1", "microemulsion saturation", 1.0),
    ("c_polymer", KR.P_CP, "ppm", "polymer concentration in the polymer-carrying phase",
     units.wt_percent_to_polymer_ppm(1.0)),
    ("c_surfactant", KR.P_CS, "ppm", "surfactant in the fluid, by volume per pore volume (overall)",
     units.volume_fraction_to_surfactant_ppm(1.0)),
    ("salinity", KR.P_SAL, "ppm", "salinity (TDS) of the water", units.anions_to_tds_ppm(1.0)),
    ("pressure", KR.P_PRES, "Pa", "pressure above the producer (the global pressure when Pc is on)", 1.0),
    ("surfactant_adsorbed", KR.P_ADS3, "ppm", "adsorbed surfactant, by volume per pore volume",
     units.volume_fraction_to_surfactant_ppm(1.0)),
    ("polymer_adsorbed", KR.P_ADS4, "ppm", "adsorbed polymer, wt-ppm x pore volume per pore volume",
     units.wt_percent_to_polymer_ppm(1.0)),
    ("oil_overall", KR.P_OIL, "1", "overall oil volume per pore volume (all phases)", 1.0),
    ("ift", KR.P_IFT, "mN/m", "controlling IFT: largest ME/excess-phase IFT present (oil-water without ME, 0 for one ME phase)", 1.0),
)


def mass_balance_errors(totals: np.ndarray) -> dict[str, float]:
    """Relative error ``|end - start - injected + produced| / (start + injected)`` per component."""
    errors = {}
    for r, name in enumerate(COMPONENTS):
        start, injected, produced, end = totals[:, r]
        scale = start + injected
        residual = abs(end - start - injected + produced)
        errors[name] = float(residual / scale) if scale > 0.0 else float(residual)
    return errors


def build_dataset(series, profiles, totals, out_pv, prof_pv, cells, attrs) -> xr.Dataset:
    """The public Dataset: series on ``pv``; profiles (if any) on (``profile_pv``, ``x``)."""
    data = {}
    for name, row, unit, long_name, sampling, scale in _SERIES:
        data[name] = xr.Variable(
            ("pv",), series[row] * scale, {"units": unit, "long_name": long_name, "sampling": sampling}
        )
    coords = {"pv": ("pv", out_pv, {"units": "1", "long_name": "injected pore volumes"})}
    if prof_pv.size:
        for name, row, unit, long_name, scale in PROFILE_VARIABLES:
            data[name] = xr.Variable(
                ("profile_pv", "x"), profiles[row] * scale, {"units": unit, "long_name": long_name}
            )
        coords["profile_pv"] = ("profile_pv", prof_pv, {"units": "1",
                                                        "long_name": "profile time, injected pore volumes"})
        coords["x"] = ("x", (np.arange(cells) + 0.5) / cells, {"units": "1", "long_name": "cell-centre x / L"})
    ds = xr.Dataset(data, coords=coords, attrs=dict(attrs))
    for name, err in mass_balance_errors(totals).items():
        ds.attrs[f"mass_balance_error_{name}"] = err
    return ds
