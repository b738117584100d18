"""The bundled study reproduces what the bundled data were made with (read from the truth file and the forward
model's catalogue, not from the study code), trains on BCF1 + BCF2, holds out BCF3 and takes no default."""

import json

import numpy as np
import pytest

import spflow
from spflow.datasets.regenerate import read_truth
from spflow.io import load_coreflood
from spflow.plugins.design.thesis_tables import TABLE_3_2
from spflow.plugins.forward.parameters import PARAMETERS
from spflow.plugins.forward.schedule import BCF_SCHEDULES
from spflow.synthetic import NoiseModel

CORE = ("LENGTH", "DIAMETER", "PORO", "PERM", "SWI", "QINJ")


@pytest.fixture(scope="module")
def study():
    return spflow.bundled_study()


def test_roles(study):
    assert [e.name for e in study.by_role("calibration")] == ["BCF1", "BCF2"]
    assert [e.name for e in study.by_role("heldout")] == ["BCF3"] and study.by_role("predict") == []


def test_core_rate_schedule_and_measurement_are_those_of_the_data(study):
    truth = read_truth()
    assert not set(truth["params"]) & set(CORE)  # the truth kept the catalogue's core, so the defaults are it
    defaults = {p.name: p.default for p in PARAMETERS}
    for e in study.experiments:
        assert {k: e.model_params()[k] for k in CORE} == {k: defaults[k] for k in CORE}
        assert e.schedule == BCF_SCHEDULES[e.name]
        assert e.noise_model() == NoiseModel.from_mapping(truth["noise"])


def test_parameter_space_effects_and_no_defaults(study):
    spaces = {label: v["range"] for label, v in study.parameter_space.items()}
    expected = {{"E2C": "n_high", "E2WC": "n_low"}.get(k, k): v for k, v in TABLE_3_2.items()}
    assert spaces == expected
    assert study.parameter_space["n_high"]["names"] == ["E1C", "E2C", "E3C"]
    assert {k: study.effects[k] for k in read_truth()["effects"]} == {k: 0.0 for k in read_truth()["effects"]}
    assert study.defaults_taken == ()
    assert "defaults taken: none" in study.describe()


def test_observations_are_the_bundled_files(study):
    e = study.experiment("BCF2")
    ds, raw = e.observations(), load_coreflood("BCF2")
    for name in raw.variables:
        np.testing.assert_array_equal(ds[name].values, raw[name].values)
    assert json.loads(ds.attrs["schedule"]) == json.loads(raw.attrs["schedule"])
    assert ds.attrs["permeability_md"] == 700.0


def test_forward_experiments_of_the_heldout_role(study):
    (heldout,) = study.forward_experiments(roles=["heldout"])
    assert heldout["name"] == "BCF3" and heldout["params"]["QINJ"] == 0.25
    assert sum(s["pv"] for s in heldout["schedule"]["slugs"]) == pytest.approx(BCF_SCHEDULES["BCF3"].total_pv)
    json.dumps(study.to_dict())
