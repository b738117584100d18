"""Every pipeline runs on a study (issue 19): the builders take ``study=`` (``None``: the bundled study, BCF1 + BCF2
calibrating and BCF3 held out; ``profile="thesis"``: BCF1 alone), the study's experiments reach every simulating and
observing node with their own core, rate and schedule, and ``spflow run|status|report --study FILE`` print the
study's defaults at the start. The values checked against are typed here from the study files and Table 2.5."""

import hashlib
from pathlib import Path

import numpy as np
import pytest

import spflow
import spflow.cli
from spflow.core.overrides import apply_overrides
from spflow.pipelines import bayesian_calibration, gap_diagnosis, history_matching, slug_design, workflow

BUNDLED_CORE = {"LENGTH": 0.1524, "DIAMETER": 0.0508, "PORO": 0.23, "PERM": 700.0, "SWI": 0.2, "QINJ": 0.25}


def _names(experiments):
    return [e if isinstance(e, str) else e["name"] for e in experiments]


def test_bundled_default_trains_on_bcf1_and_bcf2_and_holds_out_bcf3():
    p = history_matching.pipeline(quick=True)
    assert _names(p.nodes["responses"].params["experiments"]) == ["BCF1", "BCF2"]
    assert p.nodes["surrogate"].params["experiments"] == ["BCF1", "BCF2"]
    cal = p.nodes["calibration"].params
    assert cal["training"] == ["BCF1", "BCF2"] and _names(cal["held_out"]) == ["BCF3"]
    held = cal["held_out"][0]
    assert held["params"] == pytest.approx(BUNDLED_CORE)
    assert [s["pv"] for s in held["schedule"]["slugs"]] == [1.6, 0.25, 0.25, 0.51, 1.49]  # Table 2.5, BCF3
    assert _names(p.nodes["observations"].params["experiments"]) == ["BCF1", "BCF2", "BCF3"]
    assert _names(p.nodes["validation"].params["experiments"]) == ["BCF1", "BCF2", "BCF3"]


def test_the_chapter_3_and_4_pipelines_calibrate_the_studys_space_or_under_the_thesis_profile_its_tables():
    """Study profile: one design column per label of [parameters.calibrated] (bundled: Table 3.2's ranges, n_high /
    n_low setting all three phases' exponents); thesis profile: Tables 3.2 and 4.1 as typed here from the thesis."""
    for module in (history_matching, bayesian_calibration):
        space = module.pipeline(quick=True).nodes["space"].params
        assert space["names"] == ["ALPHAV2", "HBNC70", "HBNC71", "AD31", "GAMHF", "CRK", "n_high", "n_low", "ALPHAL1"]
        assert space["ranges"]["n_high"] == {"names": ["E1C", "E2C", "E3C"], "range": [1.5, 3.0], "scale": "linear"}
    w = workflow.pipeline(quick=True)
    assert w.nodes["hm.space"].params == w.nodes["bc.space"].params == history_matching.pipeline().nodes["space"].params
    table_3_2 = {"ALPHAV2": [0.0, 3.0], "HBNC70": [0.02, 0.05], "HBNC71": [0.01, 0.02], "AD31": [0.0, 2.0],
                 "GAMHF": [55.0, 100.0], "CRK": [0.05, 0.1], "E2C": [1.5, 3.0], "E2WC": [1.5, 3.0],
                 "ALPHAL1": [0.008, 0.012]}
    table_4_1 = {"ALPHAV2": [2.5, 3.0], "HBNC70": [0.02, 0.035], "HBNC71": [0.01, 0.02], "AD31": [0.1, 1.0],
                 "GAMHF": [50.0, 70.0], "CRK": [0.06, 0.08], "E2C": [1.5, 2.5], "E2WC": [1.5, 2.5],
                 "ALPHAL1": [0.008, 0.012]}
    for module, table in ((history_matching, table_3_2), (bayesian_calibration, table_4_1)):
        space = module.pipeline(quick=True, profile="thesis").nodes["space"].params
        assert space["names"] == list(table) and space["ranges"] == table
    t = workflow.pipeline(quick=True, profile="thesis")
    assert t.nodes["hm.space"].params["ranges"] == table_3_2 and t.nodes["bc.space"].params["ranges"] == table_4_1


def test_thesis_profile_trains_on_bcf1_alone():
    for module in (history_matching, bayesian_calibration):
        p = module.pipeline(quick=True, profile="thesis")
        assert _names(p.nodes["responses"].params["experiments"]) == ["BCF1"]
    cal = history_matching.pipeline(quick=True, profile="thesis").nodes["calibration"].params
    assert cal["training"] == ["BCF1"] and _names(cal["held_out"]) == ["BCF2", "BCF3"]
    post = bayesian_calibration.pipeline(quick=True, profile="thesis").nodes["posterior"].params
    assert post["experiments"] == ["BCF1"]
    with pytest.raises(spflow.ParameterError, match="profile 'thesys' is not one of"):
        history_matching.pipeline(profile="thesys")


def test_observation_sources_carry_the_data_digest_and_the_studys_core():
    study = spflow.bundled_study()
    source = study.experiment("BCF3").observation_source()
    assert source["sha256"] == hashlib.sha256(Path(source["data"]).read_bytes()).hexdigest()
    assert source["attrs"]["core_length_m"] == 0.1524 and source["attrs"]["experiment"] == "BCF3"
    gap = gap_diagnosis.pipeline(quick=True).nodes["diagnosis"].params
    assert _names(gap["calibration"]) == ["BCF1", "BCF2"] and _names(gap["heldout"]) == ["BCF3"]
    assert set(gap["base"]["parameters"]) == set(study.parameter_space) and gap["base"]["cells"] == 30


def test_a_changed_data_file_is_refused_until_the_study_is_read_again(tmp_path):
    from spflow.io.observed_source import load_observed

    source = spflow.bundled_study().experiment("BCF1").observation_source()
    copy = tmp_path / "BCF1.nc"
    copy.write_bytes(Path(source["data"]).read_bytes() + b"\0")
    with pytest.raises(ValueError, match="changed after the study was read"):
        load_observed(dict(source, data=str(copy)))
    with pytest.raises(ValueError, match=r"unknown key\(s\) \['core'\]"):
        load_observed(dict(source, core={}))


def test_slug_design_reference_flood_is_the_first_training_sp_flood():
    nodes = slug_design.pipeline(quick=True).nodes
    params = nodes["design_up"].params
    slugs = params["reference_flood"]["slugs"]
    assert params["reference_flood"]["name"] == "BCF1"
    assert [s["pv"] for s in slugs] == [1.45, 0.5, 1.01, 1.27]  # Table 2.5, BCF1
    assert {k: params["fixed"][k] for k in BUNDLED_CORE} == pytest.approx(BUNDLED_CORE)
    thesis = slug_design.pipeline(quick=True, reference="thesis").nodes["design_up"].params
    assert thesis["reference_flood"] == {}


def test_workflow_parts_share_one_study():
    p = workflow.pipeline(quick=True)
    for node in ("hm.responses", "bc.responses", "proxy.responses"):
        assert _names(p.nodes[node].params["experiments"]) == ["BCF1", "BCF2"], node
    assert _names(p.nodes["screening.screening"].params["experiments"]) == ["BCF1"]
    assert _names(p.nodes["proxy.adaptive"].params["experiments"]) == ["BCF1", "BCF2"]


def test_a_study_that_omits_the_measurement_chain_prints_its_defaults_at_run_start(tmp_path, monkeypatch, capsys):
    from study_project import write_project

    monkeypatch.chdir(tmp_path)
    write_project(tmp_path)  # core7: only dead_volume_ml of the measurement chain is given
    assert spflow.cli.main(["status", "gap_diagnosis", "--study", "study.toml", "--quick"]) == 0
    out = capsys.readouterr().out.splitlines()
    assert out[0] == "pipeline 'gap_diagnosis': built-in (spflow.pipelines.gap_diagnosis)"
    assert out[1].startswith(f"study {tmp_path / 'study.toml'} (version 1): 1 experiment(s) — calibration: core7")
    for field, value in [("pressure_relative", "0.02 1"), ("pressure_ar1", "0.8 1"), ("pressure_offset_pa", "150 Pa"),
                         ("tube_pv", "0.05 PV")]:
        assert any(line.startswith(f"  DEFAULT experiment 'core7': measurement.{field} = {value} (")
                   for line in out), field
    assert out[-1].split() == ["diagnosis", "diagnose", "stale", "—", "never", "run"]


_CSV_NC_STUDY = """version = 1
[parameters.calibrated]
E2WC = [1.5, 3.0]
[parameters.fixed]
VIS1 = 1.0
VIS2 = 13.8
C50 = 0.145
C60 = 0.0097
[[experiment]]
name = "poly7"
role = "calibration"
data = "{data}"
rate = "0.5 ml/min"
schedule = [
  {{ name = "WF", pv = 1.2, salinity_ppm = 9400 }},
  {{ name = "P", pv = 0.8, salinity_ppm = 9400, polymer_ppm = 1500 }},
  {{ name = "CW", pv = 1.0, salinity_ppm = 9400 }},
]
[experiment.core]
length = "0.30 m"
diameter = "1.5 in"
porosity = "0.19"
permeability = "350 mD"
swi = "0.28"
[experiment.measurement]
{chain}
"""


def test_a_csv_and_a_netcdf_of_the_same_data_give_the_same_diagnosis(tmp_path, monkeypatch):
    from new_user_data import CHAIN, CORE, POLYMER, lab_csv

    from spflow.synthetic import make_coreflood

    monkeypatch.chdir(tmp_path)
    ds = make_coreflood({"name": "WF-P-CW", "slugs": POLYMER}, CORE, noise=CHAIN, seed=3, cells=16, pv_step=0.01,
                        experiment="poly7")
    lab_csv(ds, tmp_path / "poly7.csv")  # dp (in psi), oil cut and recovery: what the netCDF then holds too
    ds.drop_vars(["c_polymer_out", "c_surfactant_out", "salinity_out"]).to_netcdf(tmp_path / "poly7.nc")
    chain = "\n".join(f"{k} = {v!r}" for k, v in vars(CHAIN).items())
    reports = {}
    for kind in ("csv", "nc"):
        (tmp_path / f"{kind}.toml").write_text(_CSV_NC_STUDY.format(data=f"poly7.{kind}", chain=chain))
        p = gap_diagnosis.pipeline(study=f"{kind}.toml", cells=12, quick=True)
        apply_overrides(p, ['diagnosis.catalogue=["capillary_pressure"]', "diagnosis.max_nfev=4",
                            "diagnosis.replicates=10"])
        reports[kind] = spflow.run(p, cache=tmp_path / f"cache_{kind}")["diagnosis"]
    csv, nc = reports["csv"], reports["nc"]
    assert csv.attrs["verdict"] == nc.attrs["verdict"]
    assert set(csv.data_vars) == set(nc.data_vars)
    for name in nc.data_vars:
        if np.issubdtype(nc[name].dtype, np.floating):
            np.testing.assert_allclose(csv[name].values, nc[name].values, rtol=1e-6, atol=1e-12, err_msg=name)


def test_profile_and_study_options_are_checked_against_the_pipeline(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert spflow.cli.main(["status", "history_matching", "--profile", "thesis", "--quick"]) == 0
    out = capsys.readouterr().out.splitlines()
    assert out[1] == "--profile thesis"
    assert spflow.cli.main(["status", "screening", "--profile", "thesis", "--quick"]) == 2
    assert "pipeline 'screening' takes no --profile" in capsys.readouterr().err
    assert spflow.cli.main(["status", "prior_spread", "--study", "nowhere.toml"]) == 2
    assert "nowhere.toml" in capsys.readouterr().err
    assert spflow.cli.main(["diagnose", "--base", "x.toml"]) == 2
    assert "needs --study STUDY, or --observations FILE ... with --base CONFIG" in capsys.readouterr().err
    assert spflow.cli.main(["diagnose", "--study", "s.toml", "--observations", "BCF1"]) == 2
    assert "--study gives the corefloods" in capsys.readouterr().err
