"""The ``pck`` and ``gp`` stages: same wiring as ``pce`` (a pipeline swaps the proxy with set_stage), outputs that
pass the SURROGATE schema after the cache's netCDF round trip, reproduce the simulator at the training design and
carry a positive variance away from it; bad parameters fail before any work."""

import numpy as np
import pytest

import spflow
from spflow.core.errors import ParameterError
from spflow.plugins.surrogates.contract import load_surrogate
from spflow.plugins.surrogates.kriging_stage import GPStage, PCKStage
from spflow.plugins.surrogates.training_data import training_set


def _pipeline():
    p = spflow.Pipeline("proxy")
    p.add("space", "parameter_space", params={"names": ["AD31", "E2WC"], "ranges": {"AD31": [0.0, 2.0],
                                                                                   "E2WC": [1.5, 3.0]}})
    p.add("design", "lhs_design", inputs={"space": "space"}, params={"samples": 14, "seed": 3})
    p.add("test_design", "lhs_design", inputs={"space": "space"}, params={"samples": 4, "seed": 4})
    for name, design in (("responses", "design"), ("test_responses", "test_design")):
        p.add(name, "forward", inputs={"design": design}, params={"experiments": ["BCF1"], "cells": 20})
    p.add("proxy", "pce", inputs={"space": "space", "design": "design", "responses": "responses"},
          params={"degree_max": 2})
    return p


def test_pipeline_swaps_pce_for_pck_and_gp(tmp_path):
    p = _pipeline()
    first = spflow.run(p, cache=tmp_path, verbose=False)
    assert first["proxy"].attrs["surrogate"] == "pce"
    train = training_set(first["space"], first["design"], first["responses"], ["dp", "recovery"], ["BCF1"])
    test = training_set(first["space"], first["test_design"], first["test_responses"], ["dp", "recovery"], ["BCF1"])
    for stage, params in (("pck", {"share": "variable", "restarts": 2, "degree_max": 2}),
                          ("gp", {"share": "variable", "restarts": 2, "kernel": "matern52"})):
        result = spflow.run(p.set_stage("proxy", stage, params), cache=tmp_path, verbose=False)
        assert result.executed == ["proxy"]  # the simulator runs are reused from the cache
        ds = result["proxy"]
        assert ds.attrs["surrogate"] == stage and ds.attrs["share"] == "variable"
        assert ds.sizes["group"] == 2 and ds.sizes["train"] == 14  # one length-scale set per variable
        model = load_surrogate(ds)
        mean, var = model.predict(train.x)
        scale = train.y.std(axis=0).max()
        # near-interpolation: the nugget (default NUGGET) leaves a residual ~ nugget x ||R^-1 y||, which reaches ~1e-3 of the
        # scale when the fitted length-scales are long (the GP picked 6-11 unit-box lengths on these 14 runs)
        np.testing.assert_allclose(mean, train.y, atol=3e-3 * scale)
        mean_t, var_t = model.predict(test.x)
        varying = train.y.std(axis=0) > 1e-6 * np.abs(train.y).max(axis=0)
        assert (var_t[:, varying] > 0).all()
        assert np.isfinite(mean_t).all()


@pytest.mark.parametrize(("cls", "params", "match"), [
    (PCKStage, {"mode": "best"}, "mode"),
    (PCKStage, {"kernel": "cubic"}, "kernel"),
    (GPStage, {"share": "everything"}, "share"),
    (GPStage, {"restarts": 0}, "restarts"),
    (GPStage, {"nugget": -1e-3}, "nugget"),
    (PCKStage, {"degree_max": 0}, "degree_max"),
    (PCKStage, {"variables": ["dp", "dp"]}, "variables"),
    (GPStage, {"variables": ["pressure"]}, "variables"),
])
def test_bad_stage_parameters_fail_at_construction(cls, params, match):
    with pytest.raises(ParameterError, match=match):
        cls(**params)


def test_gp_stage_reports_its_length_scale_fits():
    from test_pce_stages import _design, _points, _responses, _space

    from spflow.core.stage import StageContext

    x = _points(12, 1)
    reports = []
    ctx = StageContext("gp", verbose=False, report=lambda *report: reports.append(report))
    GPStage(variables=["dp", "recovery"], experiments=["BCF1"], share="variable", restarts=1).run(
        ctx, space=_space(), design=_design(x), responses=_responses(x))
    # one length-scale set per variable: two fits, reported from 0 to 2
    assert reports[0] == ("gp", 0, 2, "length-scale fits") and reports[-1] == ("gp", 2, 2, "length-scale fits")
