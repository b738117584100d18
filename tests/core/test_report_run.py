"""The HTML report of a small run, read back with ``html.parser``: its tables are HTML tables with the units in their
headers, each section's warnings come before the section's body, and the DAG is an inline SVG with one box per
pipeline node, filled by what the run did with it."""

from __future__ import annotations

import textwrap
from html.parser import HTMLParser

import pytest
from helpers import toy_plugin

from spflow.cli import main
from spflow.core.dag_svg import STATE_COLOURS
from spflow.core.report_table import Table

PIPELINE = textwrap.dedent(
    """
    import spflow
    from spflow.core.report_table import Table

    def pipeline():
        p = spflow.Pipeline("reporttest")
        p.add("src", "toy_source", params={"value": 2.0, "n": 3})
        p.add("a", "toy_scale", inputs={"data": "src"}, params={"factor": 2.0})
        p.add("b", "toy_scale", inputs={"data": "src"}, params={"factor": 3.0})
        p.add("total", "toy_add", inputs={"a": "a", "b": "b"})
        return p

    def report(result, outdir):
        y = result["total"]["y"].values
        return ["summary of the sums",
                Table(["index", "y", "share"], [[i, float(v), float(v) / float(y.sum())] for i, v in enumerate(y)],
                      units=["", "m", "1"], title="sums"),
                "WARNING: <the toy> is not a coreflood"]
    """
)


class Elements(HTMLParser):
    """Start tags in document order as (tag, attrs, enclosing section id, text inside it) and table headers."""

    def __init__(self):
        super().__init__()
        self.tags: list[tuple[str, dict, str | None]] = []
        self.section: str | None = None
        self.headers: list[str] = []
        self.in_th = False

    def handle_starttag(self, tag, attrs):
        attrs = dict(attrs)
        if tag == "section":
            self.section = attrs.get("id")
        if tag == "th":
            self.in_th, self.headers = True, self.headers + [""]
        self.tags.append((tag, attrs, self.section))

    def handle_endtag(self, tag):
        if tag == "section":
            self.section = None
        if tag == "th":
            self.in_th = False

    def handle_data(self, data):
        if self.in_th:
            self.headers[-1] += data


@pytest.fixture
def workdir(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "pipelines").mkdir()
    (tmp_path / "pipelines" / "reporttest.py").write_text(PIPELINE)
    with toy_plugin():
        yield tmp_path


def parsed(workdir) -> Elements:
    page = Elements()
    page.feed((workdir / "out" / "reporttest" / "report.html").read_text())
    return page


def test_report_of_a_small_run(workdir, capsys):
    assert main(["run", "reporttest"]) == 0
    out = capsys.readouterr().out
    # the terminal gets the table as aligned text: y = 2 * arange(3) * 2 + 2 * arange(3) * 3 = [0, 10, 20]
    assert "index  y [m]  share [1]" in out and "2      20     0.6667" in out
    page = parsed(workdir)
    # the report's section ("Summary"): the warning first, then the body in order: text, the table with units in its
    # header, the rest of the text (where the warning line also stays)
    body = [(tag, attrs) for tag, attrs, section in page.tags if section == "s1" and tag in ("p", "pre", "table")]
    assert [tag for tag, _ in body] == ["p", "pre", "table", "pre"] and body[0][1]["class"] == "warning"
    assert ["index", "y [m]", "share [1]"] == [h.strip() for h in page.headers[:3]]
    assert "time [s]" in [h.strip() for h in page.headers]  # the provenance table's unit too
    # the DAG: one box per pipeline node, all computed in this run
    boxes = {attrs["data-node"]: attrs["data-state"] for tag, attrs, _ in page.tags
             if tag == "g" and attrs.get("class") == "dag-node"}
    assert boxes == dict.fromkeys(["src", "a", "b", "total"], "ran")
    fills = [attrs["fill"] for tag, attrs, _ in page.tags if tag == "rect"][:4]
    assert fills == [STATE_COLOURS["ran"]] * 4
    # the same report from the cache: every node drawn as cached
    assert main(["report", "reporttest"]) == 0
    boxes = {attrs["data-node"]: attrs["data-state"] for tag, attrs, _ in parsed(workdir).tags
             if tag == "g" and attrs.get("class") == "dag-node"}
    assert boxes == dict.fromkeys(["src", "a", "b", "total"], "cached")


def test_a_table_refuses_rows_that_do_not_fit_its_columns():
    with pytest.raises(ValueError, match="row 1 has 1 cells, the table has 2 columns"):
        Table(["a", "b"], [[1, 2], [3]])
    with pytest.raises(ValueError, match="2 columns but 1 units"):
        Table(["a", "b"], [], units=["m"])


def test_a_failed_run_writes_a_report_with_the_failed_node(workdir, capsys):
    (workdir / "pipelines" / "failtest.py").write_text(textwrap.dedent("""
        import spflow

        def pipeline():
            p = spflow.Pipeline("failtest")
            p.add("src", "toy_source")
            p.add("bad", "toy_fail", inputs={"data": "src"})
            p.add("after", "toy_scale", inputs={"data": "bad"})
            return p
    """))
    assert main(["run", "failtest"]) == 2
    assert "boom from toy_fail" in capsys.readouterr().err
    page = Elements()
    page.feed((workdir / "out" / "failtest" / "report.html").read_text())
    boxes = {attrs["data-node"]: attrs["data-state"] for tag, attrs, _ in page.tags
             if tag == "g" and attrs.get("class") == "dag-node"}
    assert boxes == {"src": "cached", "bad": "failed", "after": "not run"}
    failure = [attrs for tag, attrs, section in page.tags if section == "s1" and tag in ("p", "pre")]
    assert failure[0]["class"] == "warning"
