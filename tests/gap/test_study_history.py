"""The table of committed twin studies (scripts/gap_study_history.py) on hand-made report JSONs: each cell repeats
its report's value, missing SNR views show as "–", and a next-experiment phase gets its own row of "after" values."""

import importlib.util
import json
from pathlib import Path

import pytest

SCRIPT = Path(__file__).resolve().parents[2] / "scripts" / "gap_study_history.py"
spec = importlib.util.spec_from_file_location("gap_study_history", SCRIPT)
history = importlib.util.module_from_spec(spec)
spec.loader.exec_module(history)


def metric(value, n):
    return {"value": value, "n": n}


def test_rows_repeat_each_report_and_its_next_experiment_phase(tmp_path):
    old = {"sets": {"Δp + oil cut": {"twins": [{}] * 5, "metrics": {
        "false_alarm_null": metric(0.5, 2), "detection_snr3": metric(0.75, 4), "top1_snr3": metric(0.25, 4),
        "truth_in_set_snr3": metric(0.5, 4), "cpu_s_per_twin": metric(12.4, 5)}}}}
    study = {"false_alarm_null": metric(0.0, 3), "top1_beyond_numerics_snr3": metric(0.8, 10),
             "truth_in_set_beyond_numerics_snr3": metric(0.9, 10),
             "mean_set_size_beyond_numerics_snr3": metric(1.25, 8)}
    new = {"sets": {"Δp + oil cut": {"twins": [{}] * 7, "metrics": study,
                                     "next_experiment_heldout": {"added_as": "heldout", "twins": [], "metrics": {
                                         "done": 2, "phase": 3, "study": {
                                             "top1_beyond_numerics_snr3": {"before": metric(0.8, 10),
                                                                           "after": metric(0.9, 10)},
                                             "false_alarm_null": {"before": metric(0.0, 3),
                                                                  "after": metric(0.0, 3)}}}}}}}
    (tmp_path / "v1.json").write_text(json.dumps(old))
    (tmp_path / "v2.json").write_text(json.dumps(new))
    lines = history.history([tmp_path / "v1.json", tmp_path / "v2.json"])
    rows = [[c.strip() for c in line.strip("|").split("|")] for line in lines[2:]]
    assert len(rows) == 3
    assert rows[0] == ["v1", "Δp + oil cut", "5", "1/2", "0.750 / – / –", "0.250 / – / –", "0.500 / – / –", "–",
                       "12"]
    assert rows[1] == ["v2", "Δp + oil cut", "7", "0/3", "– / – / –", "– / – / 0.800", "– / – / 0.900", "1.25", "–"]
    assert rows[2] == ["v2 + next experiment (heldout)", "Δp + oil cut", "2 of 3 re-diagnosed", "0/3",
                       "– / – / –", "– / – / 0.900", "– / – / –", "–", "–"]
    assert len(lines[0].split("|")) == len(lines[1].split("|")) == len(lines[2].split("|"))


def test_a_file_that_is_not_a_report_is_refused_by_name(tmp_path):
    other = tmp_path / "records.json"
    other.write_text(json.dumps({"records": []}))  # an independent-world report, say
    with pytest.raises(SystemExit, match="records.json: not a report of scripts/gap_validation.py"):
        history.history([other])
