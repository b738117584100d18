"""The bundled corefloods: schema and units, bit-identical regeneration from the truth file, truth inside the
thesis's prior ranges, and a real sim-to-real gap against the default base model."""

import json
import tomllib

import numpy as np
import pytest
import xarray as xr

from spflow import datasets
from spflow.io import load_coreflood
from spflow.plugins.forward.effects import BUILTIN_EFFECTS
from spflow.plugins.forward.parameters import default_params
from spflow.plugins.forward.schedule import BCF_SCHEDULES, as_schedule
from spflow.synthetic import NoiseModel, make_coreflood

UNITS = {"dp": "Pa", "oil_cut": "1", "recovery": "1", "oil_volume": "ml", "c_polymer_out": "ppm",
         "c_surfactant_out": "ppm", "salinity_out": "ppm"}

# Thesis Table 3.2 and Table 4.1 prior ranges of the sensitive parameters (n_low = E*WC, n_high = E*C)
TABLE_3_2 = {"ALPHAV2": (0, 3), "HBNC70": (0.02, 0.05), "HBNC71": (0.01, 0.02), "AD31": (0, 2), "GAMHF": (55, 100),
             "CRK": (0.05, 0.1), "E1WC": (1.5, 3), "E1C": (1.5, 3), "ALPHAL1": (0.008, 0.012)}
TABLE_4_1 = {"ALPHAV2": (2.5, 3.0), "HBNC70": (0.02, 0.035), "HBNC71": (0.01, 0.02), "AD31": (0.1, 1.0),
             "GAMHF": (50, 70), "CRK": (0.06, 0.08), "E1WC": (1.5, 2.5), "E1C": (1.5, 2.5),
             "ALPHAL1": (0.008, 0.012)}


@pytest.fixture(scope="module")
def truth():
    with open(datasets.truth_path(), "rb") as fh:
        return tomllib.load(fh)


@pytest.mark.parametrize("name", datasets.NAMES)
def test_bundled_dataset_schema_and_units(name, truth):
    ds = load_coreflood(name)
    assert set(ds.dims) == {"pv", "pv_tube"}
    assert set(ds.data_vars) == set(UNITS)
    for var, unit in UNITS.items():
        assert ds[var].attrs["units"] == unit
    for coord in ("pv", "pv_tube", "pv_tube_start", "pv_tube_end"):
        assert ds[coord].attrs["units"] == "PV"
    assert ds["dp"].dims == ("pv",) and ds["oil_cut"].dims == ("pv_tube",)
    np.testing.assert_allclose(ds["pv_tube"], 0.5 * (ds["pv_tube_start"] + ds["pv_tube_end"]), rtol=1e-15)
    assert np.all(np.diff(ds["pv"].values) > 0) and np.all(np.diff(ds["recovery"].values) >= 0)
    assert ds["oil_cut"].min() >= 0 and ds["oil_cut"].max() <= 1 and 0 < ds["recovery"].values[-1] < 1
    slugs = as_schedule(json.loads(ds.attrs["schedule"])).slugs
    assert slugs == BCF_SCHEDULES[name].slugs
    total = BCF_SCHEDULES[name].total_pv
    assert total - 0.02 < ds["pv"].values[-1] <= total and total - 0.05 < ds["pv_tube_end"].values[-1] <= total
    assert ds.attrs["experiment"] == name and ds.attrs["measured"] == "dp oil_cut recovery"
    assert ds.attrs["seed"] == truth["experiments"][name]["seed"]
    assert NoiseModel.from_mapping({k[6:]: ds.attrs[k] for k in ds.attrs
                                    if k.startswith("noise_") and not k.endswith("_units")}) == \
        NoiseModel.from_mapping(truth["noise"])
    for key in ("source", "generator", "spflow_version", "pore_volume_ml", "ooip_ml"):
        assert key in ds.attrs
    assert not any(key.startswith("param_") or key.startswith("effect_") for key in ds.attrs)  # no truth leak


def test_bcf1_regenerates_bit_identically_from_truth_and_seed():
    from spflow.datasets.regenerate import regenerate

    fresh = regenerate("BCF1")
    with xr.open_dataset(datasets.path("BCF1")) as stored:
        assert set(stored.variables) == set(fresh.variables)
        for name in fresh.variables:
            assert np.array_equal(stored[name].values, fresh[name].values, equal_nan=True), name
        assert {k: v for k, v in stored.attrs.items() if k != "spflow_version"} == \
            {k: v for k, v in fresh.attrs.items() if k != "spflow_version"}


def test_truth_parameters_inside_thesis_ranges_but_not_defaults(truth):
    defaults = default_params()
    for name in TABLE_3_2:
        value = truth["params"][name]
        for lo, hi in (TABLE_3_2[name], TABLE_4_1[name]):
            assert lo <= value <= hi, name
        assert value != defaults[name], name
    base_strength = {e.name: e.default_strength for e in BUILTIN_EFFECTS}
    assert truth["effects"] and all(base_strength[k] == 0.0 < v for k, v in truth["effects"].items())


def test_bundled_bcf1_shows_a_gap_beyond_noise(truth):
    """The base model at the TRUE parameters still misses the data by far more than the noise does."""
    data = load_coreflood("BCF1")
    noise = NoiseModel.from_mapping(truth["noise"])
    exact = NoiseModel.exact(pressure_interval_pv=noise.pressure_interval_pv, tube_pv=noise.tube_pv,
                             dead_volume_ml=noise.dead_volume_ml)
    kw = dict(cells=truth["simulation"]["cells"], pv_step=truth["simulation"]["pv_step"], noise=exact)
    full = make_coreflood("BCF1", truth["params"], effects=truth["effects"], **kw)
    base = make_coreflood("BCF1", truth["params"], effects={k: 0.0 for k in truth["effects"]}, **kw)

    def rms(a, q):
        return float(np.sqrt(np.mean((data[q].values - a[q].values) ** 2)))

    for q in ("dp", "oil_cut", "recovery"):
        assert rms(base, q) > 3 * rms(full, q), q
