"""make_coreflood: reproducible from its seed, independent streams, input validation before any work."""

import numpy as np
import pytest
import xarray as xr

from spflow.synthetic import NoiseModel, make_coreflood, write_twins

KW = dict(cells=40, pv_step=0.01)


def test_same_seed_same_data_other_seed_other_noise():
    a = make_coreflood("BCF2", seed=5, **KW)
    b = make_coreflood("BCF2", seed=5, **KW)
    c = make_coreflood("BCF2", seed=6, **KW)
    for name in a.variables:
        assert np.array_equal(a[name].values, b[name].values, equal_nan=True), name
    for name in ("dp", "oil_volume", "c_polymer_out"):
        assert not np.array_equal(a[name].values, c[name].values), name
    assert a.attrs["seed"] == 5 and a.attrs["generator"] == "spflow.synthetic.make_coreflood"


def test_streams_are_independent_switching_off_pressure_noise_keeps_tube_readings():
    full = make_coreflood("BCF1", seed=2, **KW)
    quiet = make_coreflood("BCF1", seed=2, noise=NoiseModel(pressure_relative=0.0), **KW)
    np.testing.assert_array_equal(full["oil_volume"].values, quiet["oil_volume"].values)
    assert not np.array_equal(full["dp"].values, quiet["dp"].values)


def test_default_truth_means_default_parameters():
    assert np.array_equal(make_coreflood("BCF1", None, **KW)["dp"].values,
                          make_coreflood("BCF1", {}, **KW)["dp"].values)
    assert not np.array_equal(make_coreflood("BCF1", None, **KW)["dp"].values,
                              make_coreflood("BCF1", {"CRK": 0.08}, **KW)["dp"].values)


@pytest.mark.parametrize("kwargs, message", [
    ({"seed": -1}, r"seed must be an integer in \[0, 2\*\*63\)"),
    ({"seed": 1.5}, "seed must be an integer"),
    ({"noise": {"tube_pv": 0.1}}, "noise must be a NoiseModel"),
    ({"truth_params": {"AD31": -1.0}}, r"AD31.*allowed \[0, 10\]"),
    ({"effects": {"kinetic_adsorption": -2}}, "kinetic_adsorption"),
    ({"noise": NoiseModel(tube_pv=1.0), "schedule": [{"pv": 0.5, "salinity_ppm": 9400}]}, "must not exceed"),
])
def test_bad_input_raises_value_error_naming_the_field(kwargs, message):
    args = {"schedule": "BCF1"} | kwargs
    with pytest.raises(ValueError, match=message):
        make_coreflood(args.pop("schedule"), args.pop("truth_params", None), **args, **KW)


def test_write_twins_writes_seeded_files_and_random_only_noise_has_no_systematic_error(tmp_path):


    noise = NoiseModel.random_only()
    assert (noise.pressure_offset_pa, noise.pressure_drift_pa_per_pv, noise.dead_volume_ml) == (0.0, 0.0, 0.0)
    assert noise.pressure_relative == NoiseModel().pressure_relative > 0  # the random errors stay
    paths = write_twins(tmp_path, {"AD31": 0.8}, noise=noise, seed=5, cells=20, experiments=("BCF1", "BCF2"))
    assert [p.rsplit("/", 1)[1] for p in paths] == ["twin_BCF1.nc", "twin_BCF2.nc"]
    for k, (path, experiment) in enumerate(zip(paths, ("BCF1", "BCF2"))):
        direct = make_coreflood(experiment, {"AD31": 0.8}, noise=noise, seed=5 + k, cells=20)
        xr.testing.assert_identical(xr.load_dataset(path), direct)
