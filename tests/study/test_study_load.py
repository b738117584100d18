"""A valid study resolves every value into the forward model's units (checked against hand conversions), takes
values from the data file's metadata, records every default it takes, and serialises to JSON."""

import json
import math

import numpy as np
import pytest

import spflow
from spflow.study import StudyError, load_study
from spflow.synthetic import NoiseModel
from study_project import STUDY, data_text, write_project

INCH = 0.0254  # m, exact by definition
FOOT = 0.3048  # m, exact by definition


def test_values_come_from_study_and_data_in_forward_units(tmp_path):
    study = spflow.load_study(write_project(tmp_path))
    (e,) = study.experiments
    assert study.by_role("calibration") == [e] and study.by_role("heldout") == []
    params = e.model_params()
    # length 30 cm in the study agrees with core_length_m 0.30 in the file; diameter 1.5 in only in the file
    assert params["LENGTH"] == pytest.approx(0.30, rel=1e-12)
    assert params["DIAMETER"] == pytest.approx(1.5 * INCH, rel=1e-12)
    assert params == pytest.approx({"LENGTH": 0.30, "DIAMETER": 1.5 * INCH, "PORO": 0.19, "PERM": 350.0,
                                    "SWI": 0.28, "QINJ": 0.5, "VIS1": 1.0})
    assert e.sources["core.length"] == "study and data" and e.sources["core.diameter"] == "data"
    assert e.sources["core.permeability"] == "study" and e.sources["fluids.VIS2"] == "[parameters.fixed]"
    assert [s.pv for s in e.schedule.slugs] == [1.2, 0.8, 1.0] and e.schedule.slugs[1].polymer_ppm == 1500.0
    assert e.noise_model() == NoiseModel(dead_volume_ml=0.5)
    assert study.fixed == {"VIS2": 13.8}
    assert study.parameter_space["n_high"] == {"names": ["E1C", "E2C", "E3C"], "range": [1.5, 3.0],
                                               "scale": "linear"}
    assert study.effects["capillary_pressure"] == 0.0 and study.effects["dispersion"] == 1.0


def test_every_default_taken_is_recorded_and_described(tmp_path):
    study = load_study(write_project(tmp_path))
    taken = {(d.experiment, d.field) for d in study.defaults_taken}
    noise_fields = {"pressure_relative", "pressure_ar1", "pressure_offset_pa", "pressure_drift_pa_per_pv",
                    "pressure_interval_pv", "tube_pv", "oil_resolution_ml", "concentration_relative"}
    expected = {("core7", f"measurement.{f}") for f in noise_fields} | {("core7", "fluids.C50"),
                                                                        ("core7", "fluids.C60")}
    # effects listed in the study file: capillary_pressure only; every other registered effect is a default
    expected |= {(None, f"effects.{n}") for n in study.effects if n != "capillary_pressure"}
    assert taken == expected
    text = "\n".join(study.describe())
    assert "DEFAULT experiment 'core7': measurement.pressure_offset_pa = 150 Pa" in text
    assert "DEFAULT experiment 'core7': fluids.C50 = 0.145 meq/ml" in text
    assert "measurement.dead_volume_ml" not in {d.field for d in study.defaults_taken}


def test_to_dict_is_json_and_sees_data_content_changes(tmp_path):
    path = write_project(tmp_path)
    first = load_study(path).to_dict()
    json.dumps(first)
    (tmp_path / "core7.csv").write_text(data_text().replace("2.1,", "2.15,"))
    second = load_study(path).to_dict()
    assert first["experiments"][0]["data_sha256"] != second["experiments"][0]["data_sha256"]
    assert {k: v for k, v in first.items() if k != "experiments"} == \
        {k: v for k, v in second.items() if k != "experiments"}


def test_observations_carry_the_resolved_metadata(tmp_path):
    e = load_study(write_project(tmp_path)).experiments[0]
    ds = e.observations()
    assert ds.attrs["experiment"] == "core7"
    assert ds.attrs["core_diameter_m"] == pytest.approx(1.5 * INCH) and ds.attrs["core_diameter_m_units"] == "m"
    assert ds.attrs["permeability_md"] == 350.0 and ds.attrs["permeability_md_units"] == "mD"
    assert ds.attrs["noise_dead_volume_ml"] == 0.5
    pore = math.pi * (1.5 * INCH) ** 2 / 4 * 0.30 * 0.19 * 1e6
    assert ds.attrs["pore_volume_ml"] == pytest.approx(pore) and ds.attrs["ooip_ml"] == pytest.approx(pore * 0.72)
    assert json.loads(ds.attrs["schedule"])["slugs"][1]["polymer_ppm"] == 1500.0
    np.testing.assert_allclose(ds["dp"].values[:2], [2.1 * 6894.757293168361, 2.2 * 6894.757293168361])


@pytest.mark.parametrize("text, metres", [("0.3 m", 0.3), ("30 cm", 0.3), ("300 mm", 0.3),
                                          ("{ value = 0.3, units = \"m\" }", 0.3),
                                          ("\"11.811023622047244 in\"", 11.811023622047244 * INCH),
                                          ("\"0.984251968503937 ft\"", 0.984251968503937 * FOOT)])
def test_length_units(tmp_path, text, metres):
    value = text if text.startswith(("{", "\"")) else f'"{text}"'
    study = STUDY.replace('length = "30 cm"', f"length = {value}")
    e = load_study(write_project(tmp_path, study=study)).experiments[0]
    assert e.model_params()["LENGTH"] == pytest.approx(metres, rel=1e-12)


@pytest.mark.parametrize("rate, ml_min", [
    ("30 ml/h", 0.5), ("0.5 cc/min", 0.5), ("0.5 cm3/min", 0.5),
    # superficial velocity through a 1.5 in core: q = u * pi D^2 / 4
    ("0.14 ft/day", 0.14 * FOOT / 86400 * math.pi * (1.5 * INCH) ** 2 / 4 * 1e6 * 60),
])
def test_rate_units_including_a_velocity(tmp_path, rate, ml_min):
    study = STUDY.replace('rate = "0.5 ml/min"', f'rate = "{rate}"')
    data = data_text().replace("# rate_ml_min: 0.5\n", "")
    e = load_study(write_project(tmp_path, study=study, data=data)).experiments[0]
    assert e.model_params()["QINJ"] == pytest.approx(ml_min, rel=1e-12)


def test_percent_porosity_and_darcy_permeability(tmp_path):
    study = STUDY.replace('permeability = "350 mD"', 'permeability = "0.35 D"\nporosity = "19 %"')
    e = load_study(write_project(tmp_path, study=study)).experiments[0]
    assert e.model_params()["PERM"] == pytest.approx(350.0) and e.model_params()["PORO"] == pytest.approx(0.19)
    assert e.sources["core.porosity"] == "study and data"


def test_by_role_rejects_unknown_roles(tmp_path):
    study = load_study(write_project(tmp_path))
    with pytest.raises(StudyError, match="allowed roles: calibration, heldout, predict"):
        study.by_role("training")


PREDICT = '''
[[experiment]]
name = "design"
role = "predict"
rate = "1 ml/h"
schedule = [{ pv = 0.5, salinity_ppm = 9400, surfactant_ppm = 5000, polymer_ppm = 2000 }]
[experiment.core]
length = "1 ft"
diameter = "2 in"
porosity = "20 %"
permeability = "1 D"
swi = "0.25"
[experiment.measurement]
dead_volume_ml = 1.0
'''


def test_a_predict_experiment_may_go_without_data(tmp_path):
    study = load_study(write_project(tmp_path, study=STUDY + PREDICT))
    e = study.experiment("design")
    assert e.data is None and e.role == "predict"
    assert e.model_params() == pytest.approx({"LENGTH": FOOT, "DIAMETER": 2 * INCH, "PORO": 0.2, "PERM": 1000.0,
                                              "SWI": 0.25, "QINJ": 1 / 60})
    assert study.forward_experiments(roles=["predict"])[0]["schedule"]["slugs"][0]["surfactant_ppm"] == 5000.0
    assert study.to_dict()["experiments"][1]["data"] is None
    with pytest.raises(StudyError, match="'design' \\(predict\\) has no data file"):
        e.observations()


def test_only_predict_experiments_may_go_without_data(tmp_path):
    text = STUDY + PREDICT.replace('role = "predict"', 'role = "heldout"')
    with pytest.raises(StudyError, match="experiment 'design': field 'data' must be the path .* only role 'predict'"):
        load_study(write_project(tmp_path, study=text))
