"""The twin-study bookkeeping of scripts/gap_validation.py on hand-made records: metrics, confusion, power bins,
and the truth-strength draws (inside the physical range, never close to the base strength)."""

import importlib.util
import json
from pathlib import Path

import numpy as np
import pytest

from spflow.plugins.forward.numba_cache import source_digest

SCRIPT = Path(__file__).resolve().parents[2] / "scripts" / "gap_validation.py"
spec = importlib.util.spec_from_file_location("gap_validation", SCRIPT)
gv = importlib.util.module_from_spec(spec)
spec.loader.exec_module(gv)


def record(scenario, snr, verdict, accepted=(), ambiguity=(), truth=None, closed=None, ratio=1.0):
    return {"id": scenario, "scenario": scenario, "snr": snr, "verdict": verdict,
            "accepted": [list(a) for a in accepted],
            "ambiguity_set": list(ambiguity), "truth_effects": truth or {}, "truth_fixed": {},
            "ranking": [a[0] for a in accepted], "gap_closed_calibration": closed, "heldout_rmse_ratio": ratio,
            "coverage_heldout": [0.5, 0.9], "parameter_bias": [0.3, 0.1], "cpu_s": 10.0, "forward_runs": 100,
            "cells": 30, "variables": ["dp", "oil_cut"]}


RECORDS = [
    record("null", 0.0, "none"), record("null", 0.0, "none"), record("null", 0.0, "none"),
    record("null", 0.0, "effect", [["dispersion"]], ["dispersion"]),
    record("single:dispersion", 12.0, "effect", [["dispersion"]], ["dispersion"], {"dispersion": 3.0}, 0.9, 0.4),
    record("single:dispersion", 2.0, "none", truth={"dispersion": 1.6}),
    record("single:capillary_pressure", 50.0, "ambiguous", [["dispersion", "capillary_pressure"]],
           ["dispersion", "capillary_pressure"], {"capillary_pressure": 1.0}, 0.95, 0.2),
    record("single:capillary_pressure", 40.0, "effect", [["capillary_pressure"]], ["capillary_pressure"],
           {"capillary_pressure": 2.0}, 0.7, 0.6),
    record("out_of_catalogue", 20.0, "out_of_catalogue"),
    record("out_of_catalogue", 20.0, "effect", [["capillary_pressure"]], ["capillary_pressure"]),
]


def test_metrics_by_hand():
    m = {k: v["value"] for k, v in gv.metrics(RECORDS).items()}
    assert m["false_alarm_null"] == 0.25
    assert m["detection_snr3"] == 1.0                  # the SNR-2 twin is below the stratum
    assert m["top1_snr3"] == pytest.approx(2 / 3)       # dispersion first for the ambiguous capillary twin
    assert m["truth_in_set_snr3"] == 1.0
    assert m["mean_set_size_snr3"] == pytest.approx(4 / 3)
    assert m["ooc_flagged"] == 0.5 and m["ooc_confidently_misattributed"] == 0.5
    assert m["gap_closed_median_correct"] == pytest.approx(0.8)      # median of 0.9 and 0.7
    assert m["heldout_rmse_ratio_median_correct"] == pytest.approx(0.5)


def test_confusion_and_power():
    rows, cols, conf = gv.confusion(RECORDS)
    assert conf.sum() == len(RECORDS)
    assert conf[rows.index("null"), cols.index("none")] == 3
    assert conf[rows.index("capillary_pressure"), cols.index("dispersion")] == 1
    assert conf[rows.index("out_of_catalogue"), cols.index("out_of_catalogue")] == 1
    bins = {tuple(b["snr"]): b for b in gv.power(RECORDS)}
    assert bins[(1.0, 3.0)]["n"] == 1 and bins[(1.0, 3.0)]["detection"] == 0.0
    assert bins[(30.0, np.inf)]["n"] == 2 and bins[(30.0, np.inf)]["top1"] == 0.5


def test_truth_strengths_are_physical_and_away_from_the_base():
    cands = {c.name: c for c in gv.candidates_for(gv.CATALOGUE, gv._base(30).effects)}
    rng = np.random.default_rng(0)
    for name, c in cands.items():
        for _ in range(50):
            s = gv._strength(c, rng)
            assert c.physical[0] - 1e-12 <= s <= c.physical[1] + 1e-12
            if c.base > 0:
                assert max(s / c.base, c.base / s) >= 1.5 - 1e-9


def test_indistinguishable_set_against_hand_computed_members():
    def row(name, delta, pair_se, chi2, strength_z=3.0, physical=True, closed=0.5, passes=False):
        return {"name": name, "delta_elpd": delta, "se": 1.0, "strength_z": strength_z, "physical": physical,
                "gap_closed": closed, "chi2": chi2, "passes": passes, "pair_se": pair_se}

    r = record("single:shear_thinning", 10.0, "effect", [["a"]], ["a"], {"shear_thinning": 0.5})
    r["step0"] = [row("a", 100.0, 0.0, 80.0, passes=True),
                  row("b", 85.0, 8.0, 200.0),           # held out: 15 <= 2 * 8 -> member
                  row("c", 50.0, 10.0, 85.0),           # calibration: chi2 within 6.63 of the best -> member
                  row("d", 50.0, 10.0, 90.0),           # separated on both -> not a member
                  row("e", 120.0, 5.0, 70.0, strength_z=1.0),  # strength not significant -> only without the test
                  row("f", 99.0, 5.0, 80.0, physical=False),   # unphysical -> never
                  row("g", 99.0, 5.0, 80.0, closed=-0.1)]      # does not improve the calibration fit -> never
    assert gv.indistinguishable_set(r) == ["a", "b", "c"]
    assert gv.indistinguishable_set(r, present=False) == ["a", "e", "b", "c"]
    r["accepted"] = [["a"], ["b"]]  # accepted in a later step: "both", not "either"
    assert gv.indistinguishable_set(r) == ["a", "c"]
    r["verdict"] = "out_of_catalogue"
    assert gv.indistinguishable_set(r) == ["a"]  # the diagnosis's own set is kept without a declared effect


def test_selected_twins_keep_their_place_and_seed_in_the_study():
    specs = gv.scenarios(60, 30, 30, 30)
    groups = 1 + len(gv.CATALOGUE) + 2          # null, one per effect, pairs, out of catalogue: interleaved
    chosen = gv.select(specs, ["single:dispersion#3", "null#0"])
    assert [(s["id"], i) for s, i in chosen] == [("null#0", 0), ("single:dispersion#3",
                                                                  3 * groups + 1 + gv.CATALOGUE.index("dispersion"))]
    whole = gv.select(specs, ["single:dispersion"])
    assert len(whole) == 30 and all(s["scenario"] == "single:dispersion" for s, _ in whole)
    assert gv.select(specs, None) == [(s, i) for i, s in enumerate(specs)]
    with pytest.raises(SystemExit, match="single:gravity#1"):
        gv.select(specs, ["single:gravity#1"])


def test_rates_beyond_numerics_count_only_twins_that_record_it():
    strong = dict(record("single:dispersion", 12.0, "effect", [["dispersion"]], ["dispersion"], {"dispersion": 3.0}),
                  snr_beyond_numerics=4.0)
    within = dict(record("single:dispersion", 12.0, "none", truth={"dispersion": 1.0}), snr_beyond_numerics=1.5)
    unknown = record("single:dispersion", 12.0, "none", truth={"dispersion": 2.0})
    m = gv.metrics([record("null", 0.0, "none"), strong, within, unknown])
    assert m["detection_beyond_numerics_snr3"]["value"] == 1.0 and m["detection_beyond_numerics_snr3"]["n"] == 1
    assert m["detection_snr3"]["value"] == pytest.approx(1 / 3)
    bins = {tuple(b["snr"]): b["n"] for b in gv.power([strong, within, unknown], "snr_beyond_numerics")}
    assert bins[(1.0, 3.0)] == 1 and bins[(3.0, 10.0)] == 1 and sum(bins.values()) == 2


def test_paired_comparison_with_a_baseline_study_by_hand():
    def twin(i, verdict, ambiguity, seed=1):
        r = record("single:dispersion", 12.0, verdict, [list(ambiguity)] if ambiguity else [], ambiguity,
                   {"dispersion": 3.0})
        return r | {"id": f"single:dispersion#{i}", "seed": seed, "snr_beyond_numerics": 5.0}

    baseline = [twin(0, "effect", ["dispersion"]), twin(1, "effect", ["polymer_adsorption"]),
                twin(2, "none", []), twin(3, "effect", ["dispersion"]), twin(4, "none", [])]
    here = [twin(0, "effect", ["dispersion"]),                      # unchanged, truth in the set
            twin(1, "ambiguous", ["polymer_adsorption", "dispersion"]),  # truth entered the set
            twin(2, "effect", ["dispersion"]),                      # truth entered the set
            twin(3, "effect", ["polymer_adsorption"]),              # truth left the set
            twin(4, "none", [], seed=2),                            # another seed: not the same twin
            twin(5, "effect", ["dispersion"])]                      # not in the baseline
    lines, payload = gv._paired_section(here, baseline, "B")
    assert payload["twins"] == 4
    assert payload["truth_in_set_gained"] == ["single:dispersion#1", "single:dispersion#2"]
    assert payload["truth_in_set_lost"] == ["single:dispersion#3"]
    assert payload["changed"] == ["single:dispersion#1", "single:dispersion#2", "single:dispersion#3"]
    assert payload["baseline_metrics"]["truth_in_set_snr3"]["value"] == 0.5   # twins 0 and 3 of 4
    assert payload["metrics"]["truth_in_set_snr3"]["value"] == 0.75           # twins 0, 1 and 2 of 4
    assert gv._paired_section(here[5:], baseline, "B") == (["No twin in common with the baseline B.", ""], {})


def test_set_misses_by_hand():
    """Each miss lands in the class its truth's refit row says; twins with the truth in the set, below SNR 3 or
    not single-effect are not counted."""
    def twin(verdict, ambiguity, snr, row):
        r = record("single:dispersion", 10.0, verdict, ambiguity=ambiguity, truth={"dispersion": 0.4})
        r["snr_absorbed"] = snr
        r["step0"] = [] if row is None else [{"name": "dispersion", "delta_elpd": row[0], "se": row[1]}]
        return r

    records = [twin("unattributed", [], 5.0, (-30.0, 10.0)),      # held-out loss
               twin("unattributed", [], 5.0, (15.0, 10.0)),       # 15 <= 2 x 10: within the margin
               twin("unattributed", [], 5.0, (25.0, 10.0)),       # beyond it
               twin("none", [], 4.0, None),                        # not shortlisted
               twin("effect", ["dispersion"], 5.0, (50.0, 5.0)),   # truth in the set: not a miss
               twin("none", [], 2.0, (-5.0, 1.0)),                 # absorbed SNR below 3: not counted
               record("pair", 10.0, "none", truth={"dispersion": 1.0, "polymer_adsorption": 2.0})]
    records[-1]["snr_absorbed"] = 10.0
    assert gv.set_misses(records) == {"unattributed": {"held-out loss": 1, "gain within the margin": 1,
                                                       "gain beyond the margin": 1},
                                      "none": {"not refitted": 1}}


def test_step0_rows_say_which_test_stopped_a_candidate():
    """A candidate that beats the base but not the discrepancy competitor: its row carries the competitor's dELPD
    and SE (and the dispersion factor and chi^2 drop), and ``passes`` is False although the base test alone holds."""
    from types import SimpleNamespace

    from spflow.plugins.gap.verdict import CandidateScore, Rule

    score = CandidateScore("dispersion", 30.0, 5.0, 9.0, 0.4, -5.0, True, 0.8, 40.0, np.zeros(3),
                           competitor_delta=3.0, competitor_se=5.0, dispersion=1.2)
    step = SimpleNamespace(scores={"dispersion": score}, fits={"dispersion": SimpleNamespace(chi2=50.0)}, loo={})
    g = SimpleNamespace(steps=[step], options=SimpleNamespace(rule=Rule()))
    [row] = gv._step0(g)
    assert row["passes"] is False
    assert (row["competitor_delta"], row["competitor_se"], row["dispersion"], row["chi2_drop"]) == (3.0, 5.0, 1.2,
                                                                                                   40.0)
    # the same scores with a competitor it beats pass
    beaten = CandidateScore(**{**score.__dict__, "competitor_delta": 25.0})
    step.scores = {"dispersion": beaten}
    assert gv._step0(g)[0]["passes"] is True


def test_a_study_made_by_another_forward_model_is_not_resumed(tmp_path):
    """Twins recorded with another forward model's source digest (or none, as before it was recorded) are not mixed
    with new ones: resuming stops before any diagnosis and names both digests."""
    old = dict(record("null", 0.0, "none"), id="null#0", heldout_predictive="sampled", predictive_centre="newton",
               first_round_jacobian="difference", options_seed=0)
    for digest in (None, "0123456789abcdef"):
        row = old if digest is None else dict(old, forward_digest=digest)
        (tmp_path / "dp_oil.jsonl").write_text(json.dumps(row) + "\n")
        with pytest.raises(SystemExit, match=rf"another forward model .*{source_digest()[:16]}"):
            gv.main(["--results", str(tmp_path), "--only", "null#1"])
    # the current digest resumes (here: nothing left to run but the report of the one record)
    (tmp_path / "dp_oil.jsonl").write_text(json.dumps(dict(old, forward_digest=source_digest()[:16])) + "\n")
    assert gv.main(["--results", str(tmp_path), "--only", "null#0"]) in (0, None)


def test_another_forward_model_resumes_only_after_its_twins_are_reproduced(tmp_path, monkeypatch):
    """``--equivalence-check K`` reruns K recorded twins with this code (here a stand-in run_twin returning a given
    record): a difference in any field but timings and the digest stops the resume naming the field; exact
    reproduction records the check, and later resumes accept that digest without rerunning."""
    old = dict(record("null", 0.0, "none"), id="null#0", seed=20260101, heldout_predictive="sampled",
               predictive_centre="newton", first_round_jacobian="difference", options_seed=0,
               forward_digest="0123456789abcdef", cpu_s=10.0, wall_s=11.0, gap_closed_calibration=float("nan"))
    (tmp_path / "dp_oil.jsonl").write_text(json.dumps(old) + "\n")
    old = json.loads(json.dumps(old))  # a rerun's NaN is another float object than the stored one's
    reruns = []

    def rerun(spec, cells, seed, *rest):
        reruns.append((spec["id"], seed))
        return dict(old, forward_digest=source_digest()[:16], cpu_s=99.0, verdict=verdict)

    monkeypatch.setattr(gv, "run_twin", rerun)
    args = ["--results", str(tmp_path), "--only", "null#0", "--equivalence-check", "1"]
    verdict = "effect"
    with pytest.raises(SystemExit, match=r"null#0 is not reproduced .*\['verdict'\]"):
        gv.main(args)
    assert not (tmp_path / "dp_oil.equivalence.json").exists()
    verdict = "none"
    assert gv.main(args) in (0, None)
    assert reruns == [("null#0", 20260101)] * 2
    check = json.loads((tmp_path / "dp_oil.equivalence.json").read_text())
    assert check[0]["accepted"] == ["0123456789abcdef"] and check[0]["twins"] == ["null#0"]
    assert gv.main(args[:4]) in (0, None) and len(reruns) == 2  # accepted: no rerun, no flag needed


def test_restore_writes_a_reports_twins_back_as_the_results_files_main_reads(tmp_path):
    """--restore: every set's records and its next-experiment phase's, each file with the command the report
    lists for it (in the order main() reads them), readable by the resume path; never over an existing file."""
    first = [dict(r, id=f"{r['id']}#{k}", gap_closed_calibration=float("nan")) for k, r in enumerate(RECORDS)]
    lifted = [{"id": first[6]["id"], "seed": 1, "cells": 30}]
    report = tmp_path / "report.json"
    report.write_text(json.dumps({"commands": ["cmd first", "cmd heldout"], "sets": {
        gv.SETS["dp_oil"][0]: {"metrics": {}, "twins": first,
                               "next_experiment_heldout": {"twins": lifted, "added_as": "heldout"}}}}))
    results = tmp_path / "results"
    written = gv.restore(report, results)
    assert written == [results / "dp_oil.jsonl", gv.next_experiment_file(results, "dp_oil", "heldout")]
    back = gv._records(results / "dp_oil.jsonl", 30)
    assert list(back) == [r["id"] for r in first]
    assert [json.dumps(r) for r in back.values()] == [json.dumps(r) for r in first]  # NaN as stored JSON
    assert gv._records(written[1], 30) == {lifted[0]["id"]: lifted[0]}
    assert (results / "dp_oil.command").read_text() == "cmd first"
    assert written[1].with_suffix(".command").read_text() == "cmd heldout"
    with pytest.raises(SystemExit, match="dp_oil.jsonl"):
        gv.restore(report, results)
