"""The example third-party plugin package (``examples/spflow-example-plugin``) installed with pip into a temporary
directory and found through its entry points: its stage and effect are listed and work, checked against independent
computations; its pipeline runs by name from an empty directory; and ``examples/custom_pipeline.py`` runs with it."""

import importlib
import os
import runpy
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

import spflow
from spflow.cli import main

ROOT = Path(__file__).resolve().parents[2]
PACKAGE = ROOT / "examples" / "spflow-example-plugin"


@pytest.fixture(scope="module")
def installed(tmp_path_factory):
    target, source = tmp_path_factory.mktemp("site"), tmp_path_factory.mktemp("src") / PACKAGE.name
    shutil.copytree(PACKAGE, source)  # the build leaves build/ and *.egg-info next to the sources: not in the repo
    subprocess.run([sys.executable, "-m", "pip", "install", "--quiet", "--no-deps", "--no-build-isolation",
                    "--target", str(target), str(source)], check=True, capture_output=True, timeout=300)
    old_path, old_env = list(sys.path), os.environ.get("SPFLOW_DISABLE_PLUGINS")
    sys.path.insert(0, str(target))
    os.environ["SPFLOW_DISABLE_PLUGINS"] = ""
    importlib.invalidate_caches()
    spflow.reset_registry()
    yield target
    sys.path[:] = old_path
    os.environ["SPFLOW_DISABLE_PLUGINS"] = old_env if old_env is not None else "*"
    spflow.reset_registry()


def test_entry_point_contributes_the_stage_and_the_effect(installed):
    registry = spflow.get_registry()
    assert registry.providers["stage:breakthrough"] == "spflow_example.breakthrough"  # the class's module
    assert registry.effects["wettability_alteration"].default_strength == 0.0


def test_effect_equals_running_with_the_transformed_parameter(installed):
    with_effect = spflow.simulate("BCF2", cells=30, pv_step=0.1, effects={"wettability_alteration": 0.6})
    direct = spflow.simulate("BCF2", {"S2RWC": 0.3 * (1 - 0.5 * 0.6)}, cells=30, pv_step=0.1)
    for name in ("dp", "oil_cut", "recovery"):
        np.testing.assert_array_equal(with_effect[name].values, direct[name].values)
    with pytest.raises(spflow.ParameterError, match="wettability_alteration"):
        spflow.simulate("BCF2", cells=30, effects={"wettability_alteration": 2.0})


def test_stage_in_a_pipeline_matches_a_direct_computation(installed, tmp_path):
    p = spflow.Pipeline("example")
    p.add("space", "parameter_space", params={"names": ["AD41", "CRK"], "relative": 0.3})
    p.add("design", "lhs_design", inputs={"space": "space"}, params={"samples": 3, "seed": 1})
    p.add("runs", "forward", inputs={"design": "design"}, params={"experiments": ["BCF2"], "cells": 30})
    p.add("bt", "breakthrough", inputs={"responses": "runs"}, params={"fraction": 0.5})
    result = spflow.run(p, cache=tmp_path)
    runs, bt = result["runs"], result["bt"]
    pv = runs["pv"].values
    for s in range(3):
        cp = runs["c_polymer_out"].isel(sample=s, experiment=0).values
        dp = runs["dp"].isel(sample=s, experiment=0).values
        # the breakthrough PV lies between the last output below half the maximum and the first at or above it
        k = int(np.argmax(cp >= 0.5 * cp.max()))
        assert pv[k - 1] <= float(bt["polymer_breakthrough_pv"][s, 0]) <= pv[k]
        assert float(bt["dp_peak"][s, 0]) == dp.max()
        assert float(bt["dp_peak_pv"][s, 0]) == pv[np.argmax(dp)]


def test_plugin_pipeline_is_listed_and_runs_by_name(installed, tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert main(["list", "pipelines"]) == 0
    assert ("  breakthrough_scan (plugin spflow-example-plugin 0.1.0): Polymer breakthrough of BCF2 across a small "
            "design of polymer adsorption and permeability reduction.") in capsys.readouterr().out.splitlines()
    assert main(["run", "breakthrough_scan", "--quick", "--set", "breakthrough.fraction=0.3"]) == 0
    out = capsys.readouterr().out
    assert "pipeline 'breakthrough_scan': plugin spflow-example-plugin 0.1.0" in out
    assert "--set breakthrough.fraction=0.3 (replaces 0.5)" in out and "4 node(s) executed" in out
    written = xr.load_dataset(tmp_path / "out" / "breakthrough_scan_quick" / "breakthrough.nc")
    # the same nodes built in Python with the parameter set there: every key equal, so all come from the cache
    from spflow_example import breakthrough_pipeline

    result = spflow.run(breakthrough_pipeline.pipeline(quick=True).set_params("breakthrough", fraction=0.3))
    assert result.executed == []
    runs = result["runs"]
    pv = runs["pv"].values
    for s in range(2):
        cp = runs["c_polymer_out"].isel(sample=s, experiment=0).values
        # the breakthrough PV lies between the last output below 30 % of the maximum and the first at or above it
        k = int(np.argmax(cp >= 0.3 * cp.max()))
        assert pv[k - 1] <= float(written["polymer_breakthrough_pv"][s, 0]) <= pv[k]
        assert f"sample {s}: {float(written['polymer_breakthrough_pv'][s, 0]):.3f} PV" in out


def test_custom_pipeline_script_runs(installed, tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    runpy.run_path(str(ROOT / "examples" / "custom_pipeline.py"), run_name="not_main")["main"](
        ["--samples", "3", "--cells", "20", "--jobs", "1"])
    out = capsys.readouterr().out
    assert "executed 6 node(s)" in out and "water_wet" in out


def test_the_example_stage_passes_the_conformance_kit(installed):
    from spflow.testing import STAGE_CHECKS, check_stage
    from spflow.testing.small_inputs import small_design, small_responses, small_space

    responses = small_responses(small_design(small_space(), samples=3), experiments=("BCF2",))
    report = check_stage(spflow.get_registry().stage("breakthrough"), {"responses": responses},
                         params={"fraction": 0.4})
    assert report.passed == list(STAGE_CHECKS)
