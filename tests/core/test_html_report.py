"""The HTML report: long lines wrap instead of being cut off, warning lines stand out (escaped), and the versions of
spflow, Python and the libraries behind the results are recorded."""

import platform
import re
from importlib.metadata import version

from spflow.core.html_report import Section, write_html_report

LONG = "noise-consistent ranges: " + "x" * 400 + " the ranges are conditional on a model the data reject (see the gap)"


def _report(tmp_path, lines):
    return write_html_report(tmp_path / "report.html", "t", [Section("Calibration", lines)], []).read_text()


def test_long_lines_wrap_and_warnings_are_highlighted_and_escaped(tmp_path):
    text = _report(tmp_path, ["plain line", LONG, "WARNING: <b>HBNC71</b> undetermined", "no warning here"])
    pre_rule = re.search(r"pre \{[^}]*\}", text).group(0)
    assert "white-space: pre-wrap" in pre_rule and "overflow-x: auto" not in pre_rule
    warnings = re.findall(r"<p class='warning' role='alert'><strong>Warning.</strong> (.*?)</p>", text)
    assert warnings == [LONG, "&lt;b&gt;HBNC71&lt;/b&gt; undetermined"]
    assert "<b>HBNC71</b>" not in text
    assert LONG in text  # still in the section's text as well


def test_the_report_records_the_software_versions(tmp_path):
    text = _report(tmp_path, [])
    rows = dict(re.findall(r"<tr><td>([^<]+)</td><td>([^<]+)</td></tr>", text))
    assert rows["Python"] == platform.python_version()
    for name in ("numpy", "scipy", "xarray", "numba", "GPy", "emcee"):
        assert rows[name] == version(name)
    assert f"by spflow {version('spflow')}" in text
