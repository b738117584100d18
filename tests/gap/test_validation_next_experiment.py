"""The next-experiment phase of scripts/gap_validation.py (issue 20): which twins go in, that a twin is
regenerated from its record exactly as the first phase made it, that the added coreflood is the truth on the
proposed schedule through the lab chain, and the before/after bookkeeping of the report on hand-made records."""

import importlib.util
import json
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from spflow.io.format import schedule_json
from spflow.io.schedule_file import read_schedule_file
from spflow.plugins.forward.schedule import BCF_SCHEDULES, as_schedule
from spflow.plugins.forward.simulate import simulate
from spflow.plugins.gap.base_model import TABLE_3_2_BASE, BaseModel
from spflow.plugins.gap.design_space import design_space
from spflow.plugins.gap.verdict import VERDICTS
from spflow.synthetic import NoiseModel, measure

SCRIPT = Path(__file__).resolve().parents[2] / "scripts" / "gap_validation.py"
spec = importlib.util.spec_from_file_location("gap_validation", SCRIPT)
gv = importlib.util.module_from_spec(spec)
spec.loader.exec_module(gv)

CELLS = 10


def record(id_, scenario, snr, verdict, accepted=(), ambiguity=(), truth=None, seed=1):
    return {"id": id_, "scenario": scenario, "seed": seed, "snr": snr, "verdict": verdict,
            "accepted": [list(a) for a in accepted], "ambiguity_set": list(ambiguity), "truth_effects": truth or {},
            "truth_fixed": {}, "ranking": [a[0] for a in accepted], "gap_closed_calibration": 0.9,
            "heldout_rmse_ratio": 0.5, "coverage_heldout": [0.5, 0.9], "parameter_bias": [0.3, 0.1], "cpu_s": 10.0,
            "forward_runs": 100, "cells": 30, "variables": ["dp", "oil_cut"]}


def test_ambiguous_means_a_final_set_of_two_or_more():
    assert gv.is_ambiguous(record("a", "null", 0, "ambiguous", [["x", "y"]], ["x", "y"]))
    assert not gv.is_ambiguous(record("b", "null", 0, "effect", [["x"]], ["x"]))
    # ambiguous only in a later step: the first answer is decided, the proposal would separate nothing
    assert not gv.is_ambiguous(record("c", "null", 0, "ambiguous", [["x"], ["y", "z"]], ["x"]))
    assert not gv.is_ambiguous(record("d", "null", 0, "none"))


def test_twin_spec_from_a_record_is_the_first_phase_spec():
    for s in gv.scenarios(1, 1, 1, 1):
        stored = {"id": s["id"], "scenario": s["scenario"], "seed": 5}  # what run_twin writes of the spec
        assert gv.twin_spec(stored) == s


def test_regenerated_null_twin_is_the_lab_chain_on_the_drawn_truth_bit_for_bit():
    seed = 20261234
    base, truth, data = gv.twin(gv.twin_spec({"id": "null#3", "scenario": "null"}), CELLS, seed)
    # independent reconstruction: the first uniform draws of the twin's seed are the truth's unit-box point
    u = np.random.default_rng(seed).random(len(base.parameters))
    params = BaseModel.from_mapping(dict(TABLE_3_2_BASE, cells=CELLS)).forward_params(base.values(u))
    assert truth["effects"] == {} and truth["fixed"] == {}
    for k, name in enumerate(("BCF1", "BCF2")):
        clean = simulate(BCF_SCHEDULES[name], params, cells=CELLS, pv_step=0.005)
        expected = measure(clean, NoiseModel(), seed + k, experiment=name, source="test")
        for v in ("dp", "oil_cut", "c_polymer_out"):
            np.testing.assert_array_equal(data[k][v].values, expected[v].values)
    again = gv.twin(gv.twin_spec({"id": "null#3", "scenario": "null"}), CELLS, seed)[2]
    for a, b in zip(data, again):
        xr.testing.assert_identical(a, b)


def test_added_coreflood_is_the_truth_on_the_proposed_schedule():
    seed = 4242
    base, truth, _ = gv.twin({"id": "single:shear_thinning#0", "scenario": "single:shear_thinning",
                              "effects": ["shear_thinning"]}, CELLS, seed)
    # a design with per-slug rates (rate steps in the last polymer slug)
    design = next(d for d in design_space(BCF_SCHEDULES["BCF1"], 0.5) if d.kind == "rate_step")
    new = gv.added_coreflood(base, truth, design.schedule, seed + gv.NEXT_SEED_OFFSET, CELLS)
    u = np.random.default_rng(seed).random(len(base.parameters))
    params = base.forward_params(base.values(u))
    clean = simulate(design.schedule, params, cells=CELLS, effects=truth["effects"], pv_step=0.005)
    expected = measure(clean, NoiseModel(), seed + 2, experiment="next_experiment", source="test")
    assert new.attrs["experiment"] == "next_experiment"
    assert json.loads(new.attrs["schedule"]) == json.loads(schedule_json(design.schedule))
    for v in ("dp", "oil_cut", "c_polymer_out"):
        np.testing.assert_array_equal(new[v].values, expected[v].values)
    # the truth's effect is in it: without the effect the same chain gives another Delta-p
    plain = measure(simulate(design.schedule, params, cells=CELLS, pv_step=0.005), NoiseModel(), seed + 2,
                    experiment="plain", source="test")
    assert not np.allclose(new["dp"].values, plain["dp"].values)


RECORDS = [
    record("null#0", "null", 0.0, "none"),
    record("null#1", "null", 0.0, "ambiguous", [["dispersion", "capillary_pressure"]],
           ["dispersion", "capillary_pressure"]),
    record("cap#0", "single:capillary_pressure", 50.0, "ambiguous", [["dispersion", "capillary_pressure"]],
           ["dispersion", "capillary_pressure"], {"capillary_pressure": 1.0}, seed=7),
    record("cap#1", "single:capillary_pressure", 40.0, "effect", [["capillary_pressure"]], ["capillary_pressure"],
           {"capillary_pressure": 2.0}),
    record("disp#0", "single:dispersion", 20.0, "ambiguous", [["capillary_pressure", "polymer_adsorption"]],
           ["capillary_pressure", "polymer_adsorption"], {"dispersion": 2.0}),
    record("ads#0", "single:polymer_adsorption", 2.0, "ambiguous", [["dispersion", "polymer_adsorption"]],
           ["dispersion", "polymer_adsorption"], {"polymer_adsorption": 2.0}),
]


def lift(id_, seed, accepted, ambiguity, accuracy, verdict="effect"):
    after = {"verdict": verdict, "accepted": accepted, "ambiguity_set": ambiguity, "ranking": [a[0] for a in accepted]}
    return {"id": id_, "seed": seed, "reproduces_first_phase": True, "after": after, "cpu_s": 60.0,
            "proposal": {"label": "post-flush", "accuracy": accuracy}, "snr": 0.0, "truth_effects": {},
            "truth_fixed": {}}


LIFTS = [
    lift("cap#0", 7, [["capillary_pressure"]], ["capillary_pressure"], {"dispersion": 0.9, "capillary_pressure": 0.7}),
    lift("disp#0", 1, [["capillary_pressure"]], ["capillary_pressure"],
         {"capillary_pressure": 0.8, "polymer_adsorption": 0.6}),
    lift("ads#0", 1, [["dispersion"], ["polymer_adsorption"]], ["dispersion"],
         {"dispersion": 0.5, "polymer_adsorption": 0.4}),
    lift("stale#0", 99, [["x"]], ["x"], {}),  # a twin no longer in the first phase's results: ignored
]


def test_lift_metrics_by_hand():
    m = gv.lift_metrics(RECORDS, LIFTS)
    assert (m["ambiguous"], m["done"]) == (4, 3)  # null#1 not done yet
    # ambiguous single-effect twins done: cap#0 (truth in set, second), disp#0 (truth outside), ads#0 (SNR 2)
    assert m["all"]["before"]["correct_first"] == (0.0, 3)
    assert m["all"]["after"]["correct_first"] == pytest.approx((1 / 3, 3))      # only cap#0 is put right
    assert m["all"]["before"]["truth_in_set"] == pytest.approx((2 / 3, 3))
    assert m["all"]["after"]["truth_in_set"] == pytest.approx((1 / 3, 3))
    assert m["snr3"]["after"]["correct_first"] == (0.5, 2)
    assert m["all"]["before"]["truth_alone"] == (0.0, 3)
    assert m["all"]["after"]["truth_alone"] == pytest.approx((1 / 3, 3))
    # study-wide at SNR >= 3 (cap#0, cap#1, disp#0): top1 1/3 before, 2/3 after; false alarms unchanged (null#1
    # has no phase result yet)
    study = m["study"]
    assert study["top1_snr3"]["before"]["value"] == pytest.approx(1 / 3)
    assert study["top1_snr3"]["after"]["value"] == pytest.approx(2 / 3)
    assert study["truth_in_set_snr3"]["after"]["value"] == pytest.approx(2 / 3)
    assert study["mean_set_size_snr3"]["before"]["value"] == pytest.approx(5 / 3)
    assert study["mean_set_size_snr3"]["after"]["value"] == pytest.approx(1.0)
    assert study["false_alarm_null"]["after"]["value"] == 0.5
    # predicted vs realised over cap#0 and ads#0 (truth among the hypotheses): accuracies 0.7 and 0.4; realised:
    # cap#0 answers the truth alone, ads#0 answers dispersion first
    assert m["predicted"]["accuracy_of_truth"] == pytest.approx((0.55, 2))
    assert m["predicted"]["realised"] == (0.5, 2)


def test_unattributed_twins_join_the_phase_and_are_counted_apart():
    """An unattributed twin (candidates close the gap, none declared) is in the phase; its before/after rates are
    counted with the ambiguous ones and apart (``kinds``)."""
    perm = record("perm#0", "single:permeability_reduction", 10.0, "unattributed",
                  truth={"permeability_reduction": 2.0})
    assert gv.needs_next_experiment(perm) and gv.is_unattributed(perm) and not gv.is_ambiguous(perm)
    assert not gv.needs_next_experiment(record("x", "null", 0, "out_of_catalogue"))
    lifts = LIFTS + [lift("perm#0", 1, [["permeability_reduction"]], ["permeability_reduction"],
                          {"base": 0.3, "permeability_reduction": 0.9, "dispersion": 0.8})]
    m = gv.lift_metrics(RECORDS + [perm], lifts)
    assert (m["ambiguous"], m["unattributed"], m["phase"], m["done"]) == (4, 1, 5, 4)
    unattributed = m["kinds"]["unattributed"]["snr3"]
    assert unattributed["before"]["correct_first"] == (0.0, 1)
    assert unattributed["after"]["correct_first"] == (1.0, 1)
    assert unattributed["after"]["truth_alone"] == (1.0, 1)
    # the ambiguous ones are as in test_lift_metrics_by_hand; together at SNR >= 3: cap#0, disp#0, perm#0
    assert m["kinds"]["ambiguous"]["snr3"]["after"]["correct_first"] == (0.5, 2)
    assert m["snr3"]["after"]["correct_first"] == pytest.approx((2 / 3, 3))
    # predicted against realised now also over perm#0 (its truth is one of the hypotheses): (0.7 + 0.4 + 0.9) / 3
    assert m["predicted"]["accuracy_of_truth"] == pytest.approx((2.0 / 3, 3))
    assert m["predicted"]["realised"] == pytest.approx((2 / 3, 3))
    # split by the first phase's verdict: perm#0 alone is unattributed (predicted 0.9, answers the truth alone)
    kinds = m["predicted"]["kinds"]
    assert kinds["unattributed"]["accuracy_of_truth"] == pytest.approx((0.9, 1))
    assert kinds["unattributed"]["realised"] == (1.0, 1)
    assert kinds["ambiguous"]["accuracy_of_truth"] == pytest.approx((0.55, 2))
    assert kinds["ambiguous"]["realised"] == (0.5, 2)


def test_report_section_says_how_many_are_done(tmp_path):
    md = tmp_path / "report.md"
    gv.write_report({"Δp + oil cut": RECORDS}, md, ["test"], {"Δp + oil cut": {"calibration": LIFTS}})
    text = md.read_text()
    assert "after the proposed next experiment" in text
    assert "next-experiment phase done for 3 of 4 (partial results)" in text
    payload = json.loads(md.with_suffix(".json").read_text())
    assert payload["sets"]["Δp + oil cut"]["next_experiment_calibration"]["metrics"]["done"] == 3


def test_phase_end_to_end_on_an_ambiguous_twin(tmp_path):
    """A 12-cell shear-thinning twin whose diagnosis leaves shear thinning and the polymer's salinity dependence
    in one set (~45 s CPU): the phase regenerates it, proposes a design for exactly that set, writes the proposal,
    diagnoses with the design's coreflood as second calibration flood, and skips the twin when run again."""
    cells, seed = 12, 501000
    first = gv.run_twin({"id": "single:shear_thinning#1", "scenario": "single:shear_thinning",
                         "effects": ["shear_thinning"]}, cells, seed, gv.SETS["dp_oil"][1])
    assert gv.is_ambiguous(first), f"the test twin is no longer ambiguous ({first['ambiguity_set']}): pick another"
    (tmp_path / "dp_oil.jsonl").write_text(json.dumps(first) + "\n")
    file = gv.next_experiment_phase(tmp_path, "dp_oil", cells, 1)
    [x] = [json.loads(line) for line in file.read_text().splitlines()]
    assert x["reproduces_first_phase"]
    assert {k: x["before"][k] for k in ("verdict", "accepted", "ambiguity_set")} == \
        {k: first[k] for k in ("verdict", "accepted", "ambiguity_set")}
    assert x["truth_effects"] == first["truth_effects"]
    assert set(x["proposal"]["hypotheses"]) == set(first["ambiguity_set"])
    assert 0.0 <= x["proposal"]["worst_accuracy"] <= 1.0
    folder = tmp_path / "next_experiment" / "dp_oil" / "single_shear_thinning_1"
    assert read_schedule_file(folder / "next_experiment.toml") == as_schedule(x["proposal"]["schedule"])
    assert x["added"]["calibration"] == ["BCF1", "next_experiment"] and x["added"]["heldout"] == ["BCF2"]
    assert x["added"]["seed"] == seed + gv.NEXT_SEED_OFFSET
    assert x["after"]["verdict"] in VERDICTS
    assert x["forward_runs"]["diagnosis_after"] > 0 and x["forward_runs"]["proposal"] > 0
    gv.next_experiment_phase(tmp_path, "dp_oil", cells, 1)  # resumed: nothing left to run
    assert len(file.read_text().splitlines()) == 1
