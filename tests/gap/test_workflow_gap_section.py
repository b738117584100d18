"""The gap section of the workflow's report (``spflow run workflow`` -> report.html) holds the tables of
``spflow diagnose``: a small diagnosis (the conformance inputs' 10-cell ``diagnose`` case) stored as the workflow's
node ``gap.diagnosis``, the workflow's report built from it as the CLI builds it (the other parts' reports stubbed:
they read nodes of their own), the page parsed with ``html.parser`` and its gap tables compared with the numbers,
names and units of the stored gap Dataset itself."""

import json
import math
from html.parser import HTMLParser

import pytest
from builtin_stage_cases import CASES, Small

from spflow.core.cache import Store
from spflow.core.executor import RunResult
from spflow.core.html_report import sections_from, write_html_report
from spflow.core.plugins import get_registry
from spflow.core.stage import StageContext
from spflow.pipelines import bayesian_calibration, history_matching, screening, slug_design, workflow

SECONDS = 11.4  # the diagnosis's run time as its store record holds it


class ReportTables(HTMLParser):
    """Every ``<table>`` of a page: the title of the ``<h2>`` section it is in, its caption, its header cells as
    ``(name, unit)`` and its rows of cell texts (header row left out); and the ``<pre>`` texts of each section."""

    def __init__(self):
        super().__init__()
        self.tables, self.pre, self.section = [], {}, None
        self.field, self.text = None, ""  # the element whose text is being read, and that text

    def handle_starttag(self, tag, attrs):
        if tag == "table":
            self.tables.append({"section": self.section, "caption": "", "header": [], "rows": []})
        elif tag == "tr":
            self.tables[-1]["rows"].append([])
        elif tag == "span" and ("class", "unit") in attrs and self.field == "th":
            self.tables[-1]["header"].append((self.text.strip(), ""))  # the column's name, then its unit
            self.field, self.text = "unit", ""
        elif tag in ("h2", "caption", "th", "td", "pre"):
            self.field, self.text = tag, ""

    def handle_data(self, data):
        self.text += data

    def handle_endtag(self, tag):
        text, field = self.text.strip(), self.field
        if field == "unit" and tag == "span":
            name, _ = self.tables[-1]["header"][-1]
            self.tables[-1]["header"][-1] = (name, text.removeprefix("[").removesuffix("]"))
        elif tag != field:
            return
        elif tag == "h2":
            self.section = text
        elif tag == "pre":
            self.pre.setdefault(self.section, []).append(text)
        elif tag == "caption":
            self.tables[-1]["caption"] = text
        elif tag == "th":
            self.tables[-1]["header"].append((text, ""))
        elif tag == "td":
            self.tables[-1]["rows"][-1].append(text)
        self.field, self.text = None, ""


@pytest.fixture(scope="module")
def gap():
    params, inputs, _ = CASES["diagnose"](Small())
    return get_registry().stage("diagnose")(**params).run(StageContext("diagnose", verbose=False), **inputs)


@pytest.fixture(scope="module")
def page(gap, tmp_path_factory):
    root = tmp_path_factory.mktemp("workflow")
    store = Store(root / "cache")
    store.save("0" * 64, gap, {"stage": "diagnose", "seconds": SECONDS}, where="test")
    result = RunResult(store, {"gap.diagnosis": "0" * 64}, executed=["gap.diagnosis"])
    mp = pytest.MonkeyPatch()
    for module in (screening, history_matching, bayesian_calibration, slug_design):
        mp.setattr(module, "report", lambda result, outdir: ["(not part of this test)"])
    mp.setattr(workflow, "_proxy_report", lambda result, outdir: ["(not part of this test)"])
    try:
        lines = workflow.report(result, root / "out")
    finally:
        mp.undo()
    path = write_html_report(root / "out" / "report.html", "spflow report: workflow",
                             sections_from(root / "out", lines), [])
    parser = ReportTables()
    parser.feed(path.read_text(encoding="utf-8"))
    return parser


def _table(page, caption):
    (found,) = [t for t in page.tables if t["section"] == "Gap diagnosis" and t["caption"].startswith(caption)]
    return dict(found, rows=[r for r in found["rows"] if r])  # the header's row holds no cells


def _number(cell):
    return math.nan if cell == "-" else float(cell)


def _close(cell, value):
    """A cell shown to 4 significant digits against the Dataset's value."""
    value = float(value)
    return math.isnan(_number(cell)) if math.isnan(value) else _number(cell) == pytest.approx(value, rel=6e-4,
                                                                                             abs=1e-12)


def test_the_gap_section_has_the_verdict_and_calibration_gap_tables(page, gap):
    captions = [t["caption"] for t in page.tables if t["section"] == "Gap diagnosis"]
    assert len(captions) >= 4, captions
    verdict = _table(page, "Verdict")
    assert [name for name, _ in verdict["header"]] == ["verdict", "ambiguity set", "declared effects", "final model"]
    (row,) = verdict["rows"]
    effects = json.loads(gap.attrs["effects"])
    assert row[0] == gap.attrs["verdict"] and row[3] == gap.attrs["final_model"]
    assert row[1] == (", ".join(json.loads(gap.attrs["ambiguity_set"])) or "-")
    assert row[2] == (", ".join(e["name"] for e in effects) or "-")
    tests = _table(page, "Calibration gap")
    names = ["chi2_pvalue", "targeted_pvalue", "chi2_base", "dof"]
    assert [unit for _, unit in tests["header"]] == [gap[n].attrs["units"] for n in names]
    (row,) = tests["rows"]
    assert all(_close(cell, gap[n]) for cell, n in zip(row, names)), (row, [float(gap[n]) for n in names])
    if effects:  # the final model's strengths, in the units the gap report writes them in
        final = _table(page, "Final model's effects")
        assert final["header"][1] == ("fitted strength", gap["fitted_strength"].attrs["units"])
        assert {r[0]: _number(r[1]) for r in final["rows"]} == pytest.approx(
            {e["name"]: float(f"{e['strength']:.4g}") for e in effects})


def test_the_gap_section_has_a_candidate_row_per_candidate_with_unit_headers(page, gap):
    scores = _table(page, "Candidate scores")
    header = dict(scores["header"])
    for column, variable in (("screening z", "screen_z"), ("fitted strength", "fitted_strength"),
                             ("delta ELPD", "delta_elpd"), ("delta ELPD SE", "delta_elpd_se"),
                             ("gap closed", "gap_closed")):
        assert header[column] == gap[variable].attrs["units"], column
    columns = [name for name, _ in scores["header"]]
    rows = {r[0]: dict(zip(columns, r)) for r in scores["rows"]}
    assert sorted(rows) == sorted(str(c) for c in gap["candidate"].values)
    declared = {e["name"] for e in json.loads(gap.attrs["effects"])}
    for j, name in enumerate(str(c) for c in gap["candidate"].values):
        row, shortlisted = rows[name], bool(gap["shortlisted"][0, j])
        assert _close(row["screening z"], gap["screen_z"][0, j]), name
        if name in declared:
            assert row["state"] == "declared"
        elif not shortlisted:
            assert row["state"] == "screened out" and row["delta ELPD"] == "-" and row["passes the rule"] == ""
        if shortlisted:
            for column, variable in (("delta ELPD", "delta_elpd"), ("fitted strength", "fitted_strength"),
                                     ("gap closed", "gap_closed")):
                assert _close(row[column], gap[variable][0, j]), (name, column)
            assert row["passes the rule"] == ("yes" if bool(gap["passes"][0, j]) else "no")
    assert any(bool(s) for s in gap["shortlisted"].values[0]), "the case should refit at least one candidate"


def test_the_gap_section_has_the_gap_closed_and_no_text_summary(page, gap):
    closed = _table(page, "Gap closed")
    assert closed["caption"] == f"Gap closed ({gap.attrs['forward_runs']} forward runs, {SECONDS:.0f} s)"
    assert [unit for _, unit in closed["header"]] == ["", "1", "1", "1"]
    rows = {r[0]: r[1:] for r in closed["rows"]}
    for label, names in (("calibration", ["gap_closed_calibration", "chi2_base", "chi2_final"]),
                         ("held-out", ["gap_closed_heldout", "chi2_heldout_base", "chi2_heldout_final"])):
        assert all(_close(cell, gap[n]) for cell, n in zip(rows[label], names)), label
    # what is left as text: the files written, the notes and whether the verdict was checked along other optimiser
    # paths (the pipeline's default: not), no "verdict: ..." line
    lines = "\n".join(page.pre["Gap diagnosis"]).splitlines()
    assert any(line.startswith("wrote ") and "gap_report.nc" in line for line in lines)
    assert [line for line in lines if "verdict" in line and not line.startswith("note: ")] == [
        "verdict along other optimiser paths: not checked (path_reruns = 0)"]
