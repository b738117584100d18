"""The diagnosis summary as tables (``spflow diagnose``'s terminal lines and report.html): a hand-written summary in
the layout of ``summary.json`` goes in; the tables hold its numbers, the units the gap report writes them in, and
render as HTML tables with those units."""

import math

from spflow.core.html_report import Section, write_html_report
from spflow.core.report_table import Table, text_lines
from spflow.plugins.gap.summary_tables import summary_items

RESULT = {
    "verdict": "ambiguous", "ambiguity_set": ["capillary_pressure", "dispersion"], "final_model": "capillary_pressure",
    "effects": [{"name": "capillary_pressure", "strength": 0.9}],
    "tried_not_declared": [{"name": "kinetic_adsorption", "strength": 0.2}],
    "ranked_effects": [
        {"name": "capillary_pressure", "screen_z": 7.5, "snr": 3.0, "absorbed": 0.1, "shortlisted": True,
         "fitted_strength": 0.9, "delta_elpd": 12.25, "delta_elpd_se": 2.5, "gap_closed": 0.8, "passes": True},
        {"name": "kinetic_adsorption", "screen_z": 3.0, "snr": 1.0, "absorbed": 0.2, "shortlisted": True,
         "fitted_strength": 0.2, "delta_elpd": None, "delta_elpd_se": 1.0, "gap_closed": 0.1, "passes": False},
        {"name": "dispersion", "screen_z": 0.5, "snr": 0.1, "absorbed": 0.9, "shortlisted": False}],
    "fit": {"chi2_base": 250.0, "chi2_final": 95.0, "dof": 100.0, "chi2_heldout_base": 80.0,
            "chi2_heldout_final": None, "chi2_pvalue": 1.5e-9, "targeted_pvalue": 0.004},
    "gap_closed": {"calibration": 0.6, "heldout": 0.4}, "forward_runs": 42, "gap_cells": [],
    "numerical_error": {"variants": ["40 cells, tvd", "40 cells, upwind"],
                        "scale": {"estimate": 0.5, "lower": 0.25, "upper": 0.75, "level": 0.95, "maximum": 1.0}},
}


def _tables(result):
    return {t.title.split(" (")[0].split(":")[0]: t for t in summary_items(result, 12.4) if isinstance(t, Table)}


def test_tables_hold_the_summary_numbers_with_their_units():
    tables = _tables(RESULT)
    assert set(tables) == {"Verdict", "Final model's effects", "Calibration gap", "Candidate scores", "Gap closed",
                           "Numerical error in the error model"}
    assert tables["Final model's effects"].rows == [["capillary_pressure", 0.9]]  # the final fit's strength
    assert tables["Calibration gap"].rows == [[1.5e-9, 0.004, 250.0, 100.0]]
    assert tables["Calibration gap"].units == ["1"] * 4
    assert tables["Verdict"].rows == [["ambiguous", "capillary_pressure, dispersion", "capillary_pressure",
                                       "capillary_pressure"]]
    scores = tables["Candidate scores"]
    unit = dict(zip(scores.columns, scores.units))
    assert unit["delta ELPD"] == unit["gap closed"] == unit["screening z"] == "1"  # nats: UDUNITS "1"
    assert unit["fitted strength"] == "1"  # an effect's strength scales its mechanism (spflow list effects)
    rows = {r[0]: dict(zip(scores.columns, r)) for r in scores.rows}
    assert rows["capillary_pressure"]["state"] == "declared" and rows["capillary_pressure"]["delta ELPD"] == 12.25
    assert rows["kinetic_adsorption"]["state"] == "tried, not declared"
    tried = rows["kinetic_adsorption"]
    assert math.isnan(tried["delta ELPD"]) and tried["passes the rule"] == "no"
    assert rows["dispersion"]["state"] == "screened out" and math.isnan(rows["dispersion"]["delta ELPD"])
    closed = tables["Gap closed"]
    assert "42 forward runs, 12 s" in closed.title
    assert closed.rows[0] == ["calibration", 0.6, 250.0, 95.0] and closed.rows[1][:3] == ["held-out", 0.4, 80.0]
    assert math.isnan(closed.rows[1][3])
    scale = tables["Numerical error in the error model"]
    assert scale.rows == [[0.5, 0.25, 0.75, 0.95, 1.0, "40 cells, tvd; 40 cells, upwind"]]


def test_without_a_numerical_scale_and_an_unattributed_gap():
    result = dict(RESULT, verdict="unattributed", ambiguity_set=[], effects=[], numerical_error=None,
                  gap_cells=[{"variable": "dp", "experiment": "BCF1", "slug": "SP"}])
    items = summary_items(result, 1.0)
    assert "Numerical error in the error model" not in _tables(result)
    assert "Final model's effects" not in _tables(result)  # no effect declared: no table of them
    line, stability = [i for i in items if isinstance(i, str)]
    assert "not attributable to a catalogued mechanism; where: dp:BCF1:SP" in line
    assert stability == "verdict along other optimiser paths: not checked (path_reruns = 0)"
    assert _tables(result)["Verdict"].rows == [["unattributed", "-", "-", "capillary_pressure"]]


def test_the_report_renders_them_as_html_tables_with_units(tmp_path):
    items = summary_items(RESULT, 12.4)
    page = write_html_report(tmp_path / "report.html", "t", [Section("Gap diagnosis", items)], []).read_text()
    assert page.count("<table>") == 6 + 2  # the six tables, the (empty) provenance and the software versions
    assert "<th>delta ELPD <span class='unit'>[1]</span></th>" in page
    assert "<td class='num'>12.25</td>" in page and "<pre>" not in page.split("Gap diagnosis")[1].split("Software")[0]
    text = text_lines(items)
    assert text[0] == "Verdict" and text[1].split()[0] == "verdict"


def test_a_run_without_a_recorded_time_says_so():
    (closed,) = [t for t in summary_items(RESULT, None) if isinstance(t, Table) and t.title.startswith("Gap closed")]
    assert closed.title == "Gap closed (42 forward runs, time not recorded)"


def test_text_from_the_data_is_escaped_in_the_report(tmp_path):
    result = dict(RESULT, verdict="unattributed", final_model="base & <b>x</b>",
                  gap_cells=[{"variable": "dp", "experiment": "<script>", "slug": "SP"}])
    page = write_html_report(tmp_path / "report.html", "t", [Section("Gap diagnosis", summary_items(result, 1.0))],
                             []).read_text()
    assert "<td>base &amp; &lt;b&gt;x&lt;/b&gt;</td>" in page and "<b>x</b>" not in page
    assert "where: dp:&lt;script&gt;:SP" in page and "<script>" not in page


def test_the_diagnosis_notes_are_printed_after_the_verdict():
    result = dict(RESULT, notes=["c_surfactant_out of PF1.nc is all zero: left out", "dispersion named at ..."])
    lines = [i for i in summary_items(result, 1.0) if isinstance(i, str)]
    assert lines[:2] == ["note: c_surfactant_out of PF1.nc is all zero: left out", "note: dispersion named at ..."]


def test_reruns_along_other_optimiser_paths_are_tabled_and_a_changed_verdict_is_called_so():
    agree = {"diff_step": 0.011, "verdict": "ambiguous", "ambiguity_set": ["dispersion", "capillary_pressure"],
             "effects": {"capillary_pressure": 0.93}, "forward_runs": 40, "agrees": True}
    differ = {"diff_step": 0.009, "verdict": "effect", "ambiguity_set": ["capillary_pressure"],
              "effects": {"capillary_pressure": 0.88}, "forward_runs": 44, "agrees": False}
    items = summary_items(dict(RESULT, path_reruns=[agree]), 1.0)
    assert items[-1] == "the verdict holds along 1 of 1 other optimiser paths"
    items = summary_items(dict(RESULT, path_reruns=[agree, differ]), 1.0)
    table = items[-2]
    assert table.rows == [[0.011, "ambiguous", "dispersion, capillary_pressure", "capillary_pressure 0.93", 40, "yes"],
                          [0.009, "effect", "capillary_pressure", "capillary_pressure 0.88", 44, "no"]]
    assert items[-1].startswith("the verdict changes along 1 of 2 other optimiser paths")
    assert "uncertain between ambiguous, effect" in items[-1]
