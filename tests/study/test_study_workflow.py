"""Acceptance of issue 19, as a new user would go: in an empty directory outside the repository, two corefloods of a
core unlike Berea's (``new_user_data``: 0.30 m x 1.5 in, porosity 0.19, 0.5 ml/min, Swi 0.28, 350 mD; a
polymer-only flood as a lab CSV and an SP flood as netCDF, made by the twin generator with the documented
measurement chain ``CHAIN``) -> ``spflow init`` -> edit (roles, permeability, slugs, measurement chain) ->
``spflow check`` -> ``spflow run workflow --study study/study.toml --quick`` writes the full report; the study's
defaults are printed at the start and recorded in the report, and every part ran on the user's corefloods."""

import json
import re
from pathlib import Path

import pytest
import xarray as xr

import spflow.cli
from spflow.pipelines import workflow
from new_user_data import CORE, POLYMER, SP, edited, write_user_data

SECTIONS = ["Run settings", "Screening", "History matching", "Proxy validation", "Bayesian calibration", "Slug design",
            "Gap diagnosis", "Provenance"]


@pytest.fixture
def user_study(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert not (Path.cwd() / "pyproject.toml").exists()
    write_user_data(tmp_path)
    assert spflow.cli.main(["init", "study", "--data", "poly7.csv", "sp8.nc"]) == 0
    path = tmp_path / "study" / "study.toml"
    text = edited(path.read_text())
    # the user confirms the roles init chose: the polymer flood calibrates, the SP flood is held out
    text = re.sub(r'role = "(\w+)"  # DEFAULT[^\n]*', r'role = "\1"', text)
    path.write_text(text)
    assert spflow.cli.main(["check", "study/study.toml"]) == 0
    capsys.readouterr()
    return path


def test_workflow_quick_on_a_new_users_study(user_study, capsys):
    assert spflow.cli.main(["run", "workflow", "--study", "study/study.toml", "--quick"]) == 0
    out = capsys.readouterr().out
    start = out.split("workflow_quick:")[0]  # what was printed before any node ran
    assert "calibration: poly7; heldout: sp8" in start
    assert "  DEFAULT experiment 'poly7': fluids.VIS2 = 13.8 cP (" in start  # a default taken, before any node ran
    html = (Path("out") / "workflow_quick" / "report.html").read_text()
    for section in SECTIONS:
        assert f">{section}</h2>" in html, section
    assert "DEFAULT experiment &#x27;sp8&#x27;: fluids.C60 = 0.0097 meq/ml" in html

    # every part ran on the user's corefloods, each with its own core (values typed in new_user_data)
    cal = xr.load_dataset(Path("out") / "workflow_quick" / "history_matching" / "calibration.nc")
    assert cal.attrs["training"] == "poly7" and list(cal["experiment"].values) == ["sp8"]
    assert "undetermined" in cal.attrs and ("undetermined_warning" in cal.attrs) == bool(cal.attrs["undetermined"])
    bands = xr.load_dataset(Path("out") / "workflow_quick" / "bayesian_calibration" / "predictive.nc")
    assert list(bands["experiment"].values) == ["poly7", "sp8"]
    assert float(bands["total_pv"].sel(experiment="poly7")) == pytest.approx(sum(s["pv"] for s in POLYMER))
    slug = xr.load_dataset(Path("out") / "workflow_quick" / "slug_design" / "design_up.nc")
    reference = json.loads(slug.attrs["reference_flood"])
    assert reference["surfactant_ppm"] == SP[1]["surfactant_ppm"] and reference["s_sp"] == SP[1]["pv"]
    assert reference["polymer_ppm"] == SP[2]["polymer_ppm"] and reference["s_p"] == SP[2]["pv"]
    summary = json.loads((Path("out") / "workflow_quick" / "gap_diagnosis" / "summary.json").read_text())
    assert summary["score"] == "heldout"  # the candidates were scored on the held-out SP flood
    assert {c["experiment"] for c in summary["gap_cells"]} <= {"poly7", "sp8"}
    pipe = workflow.pipeline(study="study/study.toml", quick=True)
    for node in ("hm.responses", "bc.responses", "screening.screening"):
        params = pipe.nodes[node].params["experiments"][0]["params"]
        assert params == pytest.approx({k: CORE[k] for k in params}), node

    # status with --study: everything fresh; the report command rewrites the report from the cache
    assert spflow.cli.main(["status", "workflow", "--study", "study/study.toml", "--quick"]) == 0
    rows = capsys.readouterr().out.splitlines()[-len(pipe.nodes):]
    assert all(row.split()[2] == "fresh" for row in rows), rows
    assert spflow.cli.main(["report", "workflow", "--study", "study/study.toml", "--quick"]) == 0
    assert "report: " in capsys.readouterr().out
