"""The ensemble failure policy: a sample whose run fails gets NaN rows and a reason in the forward stage's
``failure`` variable (the stage does not abort); consumers drop failed samples with a warning or reject them."""

import numpy as np
import pytest
import xarray as xr

import spflow
from spflow.core.errors import SpflowError
from spflow.core.stage import StageContext
from spflow.plugins.forward.failures import drop_failed, reject_failed
from spflow.plugins.forward.simulate import simulate
from spflow.plugins.forward.stage import RESPONSES, Forward
from spflow.plugins.surrogates.training_data import training_set

CTX = StageContext("fwd", verbose=False)
CELLS = 20


def _design(values):
    return xr.Dataset({"values": (("sample", "param"), np.array(values, dtype=float)[:, None])},
                      coords={"sample": np.arange(len(values)), "param": ["EPHI4"]})


def test_a_sample_beyond_the_step_budget_gets_nan_rows_and_a_reason():
    # polymer with EPHI4 = 0.2 travels 1/0.2 times faster than the water: more steps than with EPHI4 = 1; the
    # explicit scheme (the budgeted default takes longer steps past half a budget this tight: test_budgeted_capillary)
    easy = simulate("BCF1", {"EPHI4": 1.0}, cells=CELLS, pv_step=0.1, capillary="explicit")
    hard = simulate("BCF1", {"EPHI4": 0.2}, cells=CELLS, pv_step=0.1, capillary="explicit")
    assert hard.attrs["n_steps"] > easy.attrs["n_steps"]
    stage = Forward(experiments=["BCF1"], cells=CELLS, max_steps=easy.attrs["n_steps"], capillary="explicit")
    with pytest.warns(UserWarning, match=r"forward: 1 of 3 samples failed.*sample 1: BCF1: .*step budget"):
        out = stage.run(CTX, design=_design([1.0, 0.2, 1.0]))
    RESPONSES.validate(out, stage="forward", port="output")
    assert list(out["failure"].values[[0, 2]]) == ["", ""]
    reason = str(out["failure"].values[1])
    assert reason.startswith("BCF1: forward simulation failed at") and f"max_steps = {easy.attrs['n_steps']}" in reason
    for name in ("dp", "recovery", "oil_cut"):
        assert np.isnan(out[name].values[1]).all()
        np.testing.assert_array_equal(out[name].values[0, 0], easy[name].values)
        np.testing.assert_array_equal(out[name].values[2, 0], easy[name].values)


def _responses(failure):
    n = len(failure)
    y = np.arange(n, dtype=float)[:, None, None] * np.ones((1, 1, 3))
    y[[i for i, f in enumerate(failure) if f]] = np.nan
    return xr.Dataset({"recovery": (("sample", "experiment", "pv"), y, {"units": "1"}),
                       "failure": ("sample", np.array(failure, dtype=str))},
                      coords={"sample": np.arange(n), "experiment": ["BCF1"], "pv": [0.0, 0.1, 0.2]})


def test_drop_failed_warns_with_the_count_and_keeps_the_rest():
    with pytest.warns(UserWarning, match=r"who: dropped 2 of 4 samples failed .*first: sample 1: BCF1: boom"):
        kept, rows = drop_failed(_responses(["", "BCF1: boom", "", "BCF1: bang"]), "who")
    assert list(rows) == [0, 2]
    np.testing.assert_array_equal(kept["recovery"].values[:, 0, 0], [0.0, 2.0])


def test_drop_failed_with_every_sample_failed_raises():
    with pytest.raises(SpflowError, match=r"who: 2 of 2 samples failed.*no sample left"):
        drop_failed(_responses(["a", "b"]), "who")


def test_reject_failed_names_the_count():
    reject_failed(_responses(["", ""]), "stage 'x'")  # nothing failed: no error
    with pytest.raises(SpflowError, match=r"stage 'x': 1 of 2 samples failed.*needs every sample"):
        reject_failed(_responses(["", "BCF2: boom"]), "stage 'x'")


def test_surrogate_training_data_drops_failed_samples():
    space = xr.Dataset({"lower": ("param", [0.0]), "upper": ("param", [10.0])}, coords={"param": ["A"]})
    design = xr.Dataset({"values": (("sample", "param"), np.array([[1.0], [2.0], [3.0]]))},
                        coords={"sample": np.arange(3), "param": ["A"]})
    with pytest.warns(UserWarning, match=r"surrogate data: dropped 1 of 3 samples"):
        data = training_set(space, design, _responses(["", "BCF1: boom", ""]), ["recovery"], ["BCF1"])
    np.testing.assert_array_equal(data.x[:, 0], [1.0, 3.0])
    assert data.y.shape[0] == 2 and np.isfinite(data.y).all()
    np.testing.assert_array_equal(data.y[:, 0], [0.0, 2.0])


def test_failure_policy_through_a_parallel_pipeline_and_the_cache(tmp_path):
    easy = simulate("BCF1", {"EPHI4": 1.0}, cells=CELLS, pv_step=0.1, capillary="explicit")
    p = spflow.Pipeline("fail").add_data("design", _design([0.2, 1.0]))
    p.add("sim", "forward", inputs={"design": "design"},
          params={"experiments": ["BCF1"], "cells": CELLS, "pv_step": 0.1, "max_steps": easy.attrs["n_steps"],
                  "capillary": "explicit"})
    with pytest.warns(UserWarning, match="1 of 2 samples failed"):
        first = spflow.run(p, cache=tmp_path, jobs=2)["sim"]  # the samples run in loky workers
    again = spflow.run(p, cache=tmp_path)  # from the store (netCDF)
    assert "sim" in again.cached and again.executed == []
    xr.testing.assert_identical(first, again["sim"])
    assert "step budget" in str(again["sim"]["failure"].values[0]) and str(again["sim"]["failure"].values[1]) == ""
    assert np.isnan(again["sim"]["dp"].values[0]).all()
    np.testing.assert_array_equal(again["sim"]["dp"].values[1, 0], easy["dp"].values)
