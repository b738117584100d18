"""Pipelines by name from any directory: the built-ins shipped in ``spflow.pipelines``, pipelines contributed through
the ``spflow.pipelines`` entry-point group, a local ``./pipelines/NAME.py`` taking precedence, the not-found message,
and ``--set node.param=value`` overrides (validated before any work, part of the provenance keys, in the report).

Every test starts in an empty temporary directory outside the repository."""

import importlib
import sys
import json
import textwrap
import warnings

import pytest
from helpers import toy_plugin

import spflow
from spflow.cli import main
from spflow.core.overrides import parse_override
from spflow.pipelines import history_matching

#: The chapter pipelines the issue names, plus the composed main job and the two front ends: the built-ins.
BUILTINS = ["bayesian_calibration", "gap_diagnosis", "history_matching", "lab_priors", "prior_spread", "screening",
            "slug_design", "workflow"]

TOY = textwrap.dedent(
    '''
    """Toy pipeline {tag}: a ramp scaled by a factor.

    More text that is not the description.
    """
    import spflow

    def pipeline():
        p = spflow.Pipeline("toy_{tag}")
        p.add("src", "toy_source", params={{"value": 2.0}})
        p.add("scaled", "toy_scale", inputs={{"data": "src"}}, params={{"factor": 2.0}})
        return p

    def report(result, outdir):
        (outdir / "sum.txt").write_text(str(float(result["scaled"]["y"].sum())))
        return ["wrote sum.txt"]
    '''
)


@pytest.fixture
def empty(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    with toy_plugin():
        yield tmp_path


def test_list_pipelines_shows_every_builtin_with_its_description(empty, capsys):
    assert main(["list", "pipelines"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[0] == "pipelines:"
    for name in BUILTINS:
        first_line = importlib.import_module(f"spflow.pipelines.{name}").__doc__.strip().splitlines()[0]
        assert f"  {name} (built-in): {first_line}" in lines
    assert main(["list"]) == 0
    out = capsys.readouterr().out
    assert "pipelines:" in out and "  workflow (built-in): " in out and "stages:" in out


def test_status_of_a_builtin_by_name_outside_the_repository(empty, capsys):
    assert main(["status", "history_matching", "--quick"]) == 0
    out = capsys.readouterr().out.splitlines()
    assert out[0] == "pipeline 'history_matching': built-in (spflow.pipelines.history_matching)"
    assert out[1] == "no --study: the bundled study"  # then the study's summary, then one line per node
    nodes = history_matching.pipeline(quick=True).nodes
    table = {line.split()[0]: line for line in out[-len(nodes):]}
    assert set(table) == set(nodes)
    for name, node in nodes.items():
        assert node.stage in table[name] and "stale — never run" in table[name]


def test_not_found_lists_the_available_names_and_how_to_add_one(empty, capsys):
    (empty / "pipelines").mkdir()
    (empty / "pipelines" / "mine.py").write_text(TOY.format(tag="mine"))
    assert main(["run", "histroy_matching"]) == 2
    err = capsys.readouterr().err
    assert "pipeline 'histroy_matching' not found" in err
    assert "Did you mean history_matching?" in err
    assert f"Available pipelines: {', '.join(sorted(BUILTINS + ['mine']))} " in err
    assert "write pipelines/histroy_matching.py defining pipeline()" in err
    assert "entry-point group 'spflow.pipelines'" in err
    assert not (empty / ".spflow").exists()


def test_a_local_file_wins_over_the_builtin_of_the_same_name(empty, capsys):
    (empty / "pipelines").mkdir()
    (empty / "pipelines" / "history_matching.py").write_text(TOY.format(tag="local"))
    assert main(["status", "history_matching"]) == 0
    out = capsys.readouterr().out.splitlines()
    assert out[0] == ("pipeline 'history_matching': local file pipelines/history_matching.py "
                      "(used instead of the built-in pipeline of that name)")
    assert [line.split()[0] for line in out[1:]] == ["src", "scaled"]  # the toy's nodes, not chapter 3's
    assert main(["list", "pipelines"]) == 0
    assert ("  history_matching (local file pipelines/history_matching.py; shadows the built-in pipeline): "
            "Toy pipeline local: a ramp scaled by a factor.") in capsys.readouterr().out.splitlines()
    # a .py path and a dotted module still work
    assert main(["status", "pipelines/history_matching.py"]) == 0
    assert capsys.readouterr().out.startswith("pipeline 'pipelines/history_matching.py': file pipelines/")
    assert main(["status", "spflow.pipelines.screening", "--quick"]) == 0
    out = capsys.readouterr().out
    assert out.startswith("pipeline 'spflow.pipelines.screening': module spflow.pipelines.screening\n")
    assert "screening  sobol_screening" in out


@pytest.fixture
def plugin_site(empty, monkeypatch):
    """An installed distribution ``fakeplug`` (a dist-info directory on sys.path) contributing three pipelines: a
    working one, one whose module does not exist, and one that tries to take a built-in's name; and a distribution
    ``otherplug`` contributing a pipeline under the working one's name."""
    site = empty / "site"
    info = site / "fakeplug-1.0.dist-info"
    info.mkdir(parents=True)
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: fakeplug\nVersion: 1.0\n")
    (info / "entry_points.txt").write_text("[spflow.pipelines]\ntoyplug = fakeplug_toy\n"
                                           "broken = fakeplug_no_such_module\nworkflow = fakeplug_toy\n")
    (site / "fakeplug_toy.py").write_text(TOY.format(tag="plug"))
    other = site / "otherplug-2.0.dist-info"
    other.mkdir()
    (other / "METADATA").write_text("Metadata-Version: 2.1\nName: otherplug\nVersion: 2.0\n")
    (other / "entry_points.txt").write_text("[spflow.pipelines]\ntoyplug = otherplug_toy\n")
    monkeypatch.syspath_prepend(str(site))
    monkeypatch.setenv("SPFLOW_DISABLE_PLUGINS", "")
    yield site
    monkeypatch.delitem(sys.modules, "fakeplug_toy", raising=False)


def _warned(*argv) -> tuple[int, str]:
    """Run the CLI; return its exit code and the PluginWarnings it issued, one per line."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        code = main(list(argv))
    return code, "\n".join(str(w.message) for w in caught if issubclass(w.category, spflow.PluginWarning))


def test_plugin_pipelines_are_listed_and_run_and_a_broken_one_is_skipped(plugin_site, capsys):
    code, err = _warned("list", "pipelines")
    assert code == 0
    out = capsys.readouterr().out.splitlines()
    assert "  toyplug (plugin fakeplug 1.0): Toy pipeline plug: a ramp scaled by a factor." in out
    assert all(any(line.startswith(f"  {name} (built-in): ") for line in out) for name in BUILTINS)
    assert not any(line.startswith("  broken ") for line in out)
    assert "pipeline 'broken' of plugin fakeplug 1.0 failed to import (fakeplug_no_such_module)" in err
    assert "pipeline 'workflow' of plugin fakeplug 1.0 ignored: a built-in pipeline has that name" in err
    assert ("pipeline 'toyplug' is contributed by fakeplug 1.0 and by otherplug 2.0; using the first (fakeplug_toy)"
            in err)

    assert main(["run", "toyplug"]) == 0
    out = capsys.readouterr().out
    assert "pipeline 'toyplug': plugin fakeplug 1.0 (fakeplug_toy)" in out
    assert "2 node(s) executed" in out
    # y = value * arange(5) scaled by 2: 2 * 2 * (0 + 1 + 2 + 3 + 4)
    assert float((plugin_site.parent / "out" / "toy_plug" / "sum.txt").read_text()) == 40.0
    assert main(["run", "broken"]) == 2
    assert "pipeline 'broken' of plugin fakeplug 1.0 failed to import" in capsys.readouterr().err


def test_disabled_plugins_contribute_no_pipelines(plugin_site, monkeypatch, capsys):
    monkeypatch.setenv("SPFLOW_DISABLE_PLUGINS", "*")
    assert main(["list", "pipelines"]) == 0
    assert "toyplug" not in capsys.readouterr().out
    monkeypatch.setenv("SPFLOW_DISABLE_PLUGINS", "broken,workflow")
    code, err = _warned("list", "pipelines")
    assert code == 0
    assert "toyplug (plugin fakeplug 1.0)" in capsys.readouterr().out
    assert "broken" not in err and "workflow" not in err and "otherplug 2.0" in err


@pytest.mark.parametrize("text, expected", [
    ("design.samples=32", ("design", "samples", 32)),
    ("hm.calibration.generations=5", ("hm.calibration", "generations", 5)),
    ("bc.posterior.samples=1e4", ("bc.posterior", "samples", 1e4)),
    ('observations.experiments=["BCF1", "BCF2"]', ("observations", "experiments", ["BCF1", "BCF2"])),
    ("design.optimization=random-cd", ("design", "optimization", "random-cd")),
    ('tag.name="32"', ("tag", "name", "32")),
    ("flag.on=true", ("flag", "on", True)),
    ("x.y=", ("x", "y", "")),
])
def test_override_values_are_json_when_they_parse_else_strings(text, expected):
    assert parse_override(text) == expected


@pytest.mark.parametrize("text", ["design.samples", "samples=3", ".samples=3", "design.=3"])
def test_malformed_override_names_the_expected_form(text):
    with pytest.raises(spflow.ParameterError, match="expected NODE.PARAM=VALUE"):
        parse_override(text)


def test_set_reruns_exactly_the_affected_nodes(empty, capsys):
    base = ["run", "history_matching", "--quick", "--until", "design"]
    assert main(base + ["--set", "design.samples=5"]) == 0
    out = capsys.readouterr().out
    assert "--set design.samples=5 (replaces 60)" in out
    assert "history_matching_quick: 2 node(s) executed, 0 from cache" in out
    # the override is the same key as the parameter set in Python: the cached design has the 5 samples
    p = history_matching.pipeline(quick=True).set_params("design", samples=5)
    result = spflow.run(p, until="design")
    assert result.executed == [] and result["design"].sizes["sample"] == 5

    assert main(base + ["--set", "design.samples=6"]) == 0
    assert "1 node(s) executed, 1 from cache" in capsys.readouterr().out  # space cached, design reran
    assert main(["status", "history_matching", "--quick", "--set", "design.samples=6"]) == 0
    rows = {line.split()[0]: line for line in capsys.readouterr().out.splitlines()[2:]}
    assert rows["space"].endswith("fresh") and rows["design"].endswith("fresh")
    assert "stale — never run" in rows["responses"]
    assert main(["status", "history_matching", "--quick"]) == 0
    rows = {line.split()[0]: line for line in capsys.readouterr().out.splitlines()[1:]}
    assert rows["design"].endswith("stale — params changed: samples: 6 -> 60")


def test_set_on_an_included_node_and_string_values(empty, capsys):
    assert main(["status", "workflow", "--quick", "--set", "hm.calibration.generations=3",
                 "--set", "bc.design.optimization=random-cd"]) == 0
    out = capsys.readouterr().out
    assert "--set hm.calibration.generations=3 (replaces 20)" in out
    assert '--set bc.design.optimization="random-cd" (replaces the stage default "none")' in out


def test_bad_overrides_are_rejected_before_any_work(empty, capsys):
    stage = spflow.get_registry().stage("lhs_design")
    bad = {
        "hm.design.samples=5": ["pipeline 'history_matching_quick' has no node 'hm.design'",
                                "its nodes (stage): space (parameter_space), design (lhs_design)",
                                "validation (forward)"],
        "design.sample=5": ["stage 'lhs_design' of node 'design' has no parameter 'sample' (did you mean samples?)",
                            f"samples (int, {stage.params['samples'].describe_range()})",
                            f"optimization (str, {stage.params['optimization'].describe_range()})"],
        "design.samples=0": ["--set design.samples=0 (node 'design'): stage 'lhs_design' parameter 'samples' = 0 is "
                             f"outside the allowed range {stage.params['samples'].describe_range()}"],
        "design.samples=many": ["parameter 'samples' must be a int, got str 'many'"],
        "design.optimization=best": ["'best' is not allowed; allowed: one of 'none', 'random-cd', 'lloyd'"],
    }
    for text, messages in bad.items():
        for command in ("run", "status", "report"):
            assert main([command, "history_matching", "--quick", "--set", "design.samples=7", "--set", text]) == 2
            captured = capsys.readouterr()
            assert captured.err.startswith(f"spflow: error: --set {text}")
            for message in messages:
                assert message in captured.err, (text, captured.err)
            assert captured.out == ""  # nothing printed, nothing planned
    assert not (empty / ".spflow").exists() and not (empty / "out").exists()


def test_overrides_are_in_the_report_and_rerun_only_their_node(empty, capsys):
    (empty / "pipelines").mkdir()
    (empty / "pipelines" / "toy.py").write_text(TOY.format(tag="report"))
    assert main(["run", "toy", "--set", "scaled.factor=3"]) == 0
    out = capsys.readouterr().out
    assert "--set scaled.factor=3.0 (replaces 2.0)" in out and "2 node(s) executed" in out
    # 2 * arange(5) * 3, summed
    assert float((empty / "out" / "toy_report" / "sum.txt").read_text()) == 60.0
    html = (empty / "out" / "toy_report" / "report.html").read_text()
    assert "Run settings" in html and "--set scaled.factor=3.0 (replaces 2.0)" in html
    assert "pipeline &#x27;toy&#x27;: local file pipelines/toy.py" in html
    assert main(["run", "toy"]) == 0
    out = capsys.readouterr().out
    assert "1 node(s) executed, 1 from cache" in out and "--set" not in out
    assert float((empty / "out" / "toy_report" / "sum.txt").read_text()) == 40.0
    assert "--set" not in (empty / "out" / "toy_report" / "report.html").read_text()
    # the saved report of the overridden run is not reused for a run without the override (and vice versa)
    assert main(["run", "toy", "--set", "scaled.factor=3"]) == 0
    out = capsys.readouterr().out
    assert "0 node(s) executed, 2 from cache" in out and "report (unchanged" not in out
    assert json.loads((empty / "out" / "toy_report" / ".report_lines.json").read_text()) == ["wrote sum.txt"]
