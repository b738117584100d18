"""The ``spflow`` command in-process: run, status (why stale), list, clean, and error reporting."""

import textwrap

import pytest
from helpers import toy_plugin

from spflow.cli import main

PIPELINE = textwrap.dedent(
    """
    import spflow
    FACTOR = {factor}

    def pipeline():
        p = spflow.Pipeline("clitest")
        p.add("src", "toy_source", params={{"value": 2.0}})
        p.add("scaled", "toy_scale", inputs={{"data": "src"}}, params={{"factor": FACTOR}})
        return p

    def report(result, outdir):
        (outdir / "sum.txt").write_text(str(float(result["scaled"]["y"].sum())))
        return ["wrote sum.txt"]
    """
)


@pytest.fixture
def workdir(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "pipelines").mkdir()
    (tmp_path / "pipelines" / "clitest.py").write_text(PIPELINE.format(factor=2.0))
    with toy_plugin():
        yield tmp_path


def test_run_status_rerun_and_clean(workdir, capsys):
    assert main(["status", "clitest"]) == 0
    assert "src" in capsys.readouterr().out
    assert main(["run", "clitest", "--jobs", "2"]) == 0
    out = capsys.readouterr().out
    assert "2 node(s) executed, 0 from cache" in out and "wrote sum.txt" in out
    # y = 2 * arange(5) * 2, summed = 40, written by the report
    assert float((workdir / "out" / "clitest" / "sum.txt").read_text()) == 40.0

    (workdir / "pipelines" / "clitest.py").write_text(PIPELINE.format(factor=3.0))
    assert main(["status", "clitest"]) == 0
    out = capsys.readouterr().out
    assert "src" in out and "fresh" in out
    assert "scaled" in out and "stale — params changed: factor: 2.0 -> 3.0" in out

    assert main(["run", "clitest"]) == 0
    assert "1 node(s) executed, 1 from cache" in capsys.readouterr().out
    assert main(["run", "clitest", "--force", "src", "--backend", "threads"]) == 0
    assert "2 node(s) executed, 0 from cache" in capsys.readouterr().out

    assert main(["clean"]) == 0
    assert "removed 3 entries" in capsys.readouterr().out
    assert not (workdir / ".spflow").exists()


def test_list_shows_stages_params_and_schemas(workdir, capsys):
    assert main(["list", "stages"]) == 0
    out = capsys.readouterr().out
    assert "toy_scale (version 1, from toy_stages)" in out
    assert "param factor: float, default 2.0, [0.0, 10.0]" in out
    assert "input data: dims ['x']; y('x',) [m]" in out


def test_errors_are_reported_without_traceback(workdir, capsys):
    (workdir / "pipelines" / "clitest.py").write_text(PIPELINE.format(factor=99.0))
    assert main(["run", "clitest"]) == 2
    err = capsys.readouterr().err
    assert "spflow: error: stage 'toy_scale' parameter 'factor' = 99.0 is outside the allowed range [0.0, 10.0]" in err
    assert main(["run", "nonexistent"]) == 2
    assert "pipeline 'nonexistent' not found" in capsys.readouterr().err


QUICK_PIPELINE = textwrap.dedent(
    """
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import spflow

    def pipeline(quick=False):
        p = spflow.Pipeline("quicktest_quick" if quick else "quicktest")
        p.add("src", "toy_source", params={"value": 1.0, "n": 3 if quick else 7})
        return p

    def report(result, outdir):
        y = result["src"]["y"].values
        fig, ax = plt.subplots()
        ax.plot(y)
        fig.savefig(outdir / "fig_3_2_ramp.png")
        plt.close(fig)
        return [f"n = {y.size}"]
    """
)


def test_quick_profile_and_html_report(workdir, capsys):
    (workdir / "pipelines" / "quicktest.py").write_text(QUICK_PIPELINE)
    assert main(["report", "quicktest", "--quick"]) == 2
    assert "1 node(s) of 'quicktest_quick' are not in the cache" in capsys.readouterr().err
    assert main(["run", "quicktest", "--quick"]) == 0
    out = capsys.readouterr().out
    assert "n = 3" in out
    html = (workdir / "out" / "quicktest_quick" / "report.html").read_text()
    assert "n = 3" in html and "Fig. 3.2: ramp" in html and "data:image/png;base64," in html
    assert "toy_source" in html and "&quot;n&quot;: 3" in html  # provenance table: stage and params
    (workdir / "out" / "quicktest_quick" / "report.html").unlink()
    assert main(["report", "quicktest", "--quick"]) == 0  # from the cache: nothing runs, the report is rewritten
    assert "report: " in capsys.readouterr().out
    assert (workdir / "out" / "quicktest_quick" / "report.html").is_file()
    assert main(["run", "clitest", "--quick"]) == 2
    assert "pipeline 'clitest' has no quick profile" in capsys.readouterr().err


def test_cached_rerun_keeps_an_up_to_date_report(workdir, capsys):
    (workdir / "pipelines" / "quicktest.py").write_text(QUICK_PIPELINE)
    assert main(["run", "quicktest"]) == 0
    figure = workdir / "out" / "quicktest" / "fig_3_2_ramp.png"
    figure.unlink()  # a redrawn report would write it again
    capsys.readouterr()
    assert main(["run", "quicktest"]) == 0
    out = capsys.readouterr().out
    assert "n = 7" in out and "report (unchanged, all nodes cached)" in out and not figure.exists()
    # an edited pipeline module (same node keys) invalidates the saved report
    (workdir / "pipelines" / "quicktest.py").write_text(QUICK_PIPELINE + "\n# edited\n")
    assert main(["run", "quicktest"]) == 0
    assert "report (unchanged" not in capsys.readouterr().out and figure.exists()
