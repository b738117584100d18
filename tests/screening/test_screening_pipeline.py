"""The screening stages inside a cached pipeline: parameter_space -> screening -> selected_space -> lhs_design.
Outputs pass schema validation after the store's netCDF round trip (bool, string and NaN variables), and a rerun
loads every node from the cache with identical results."""

import pytest
import xarray as xr

import spflow

GROUPS = {"surfactant": ["HBNC70", "ALPHAV3"], "relperm": ["E2C"]}
METHODS = {
    "sobol_screening": {"samples": 4, "calc_second_order": True, "qois": ["recovery_final", "dp_max", "dp"]},
    "morris_screening": {"trajectories": 3},
}


def _pipeline(method: str) -> spflow.Pipeline:
    p = spflow.Pipeline("screen")
    p.add("space", "parameter_space", params={"names": ["HBNC70", "E2C", "ALPHAV3"],
                                              "ranges": {"HBNC70": [0.02, 0.05], "ALPHAV3": [0.0, 3.0]}})
    p.add("screen", method, inputs={"space": "space"},
          params={"cells": 20, "groups": GROUPS, "top_k": 1, "threshold": 0.0, **METHODS[method]})
    p.add("reduced", "selected_space", inputs={"screening": "screen"})
    p.add("design", "lhs_design", inputs={"space": "reduced"}, params={"samples": 8})
    return p


@pytest.mark.parametrize("method", sorted(METHODS))
def test_screening_pipeline_round_trips_through_the_cache(tmp_path, method):
    first = spflow.run(_pipeline(method), cache=tmp_path, verbose=False)
    assert set(first.executed) == {"space", "screen", "reduced", "design"}
    screen = first["screen"]
    assert screen["selected"].dtype == bool
    assert screen["group"].values.tolist() == ["surfactant", "relperm", "surfactant"]
    # top-1 per sub-model: the binodal height beats ALPHAV3 in "surfactant"; E2C is alone in "relperm"
    assert screen["selected"].values.tolist() == [True, True, False]
    assert first["design"]["param"].values.tolist() == ["HBNC70", "E2C"]
    again = spflow.run(_pipeline(method), cache=tmp_path, verbose=False)
    assert again.executed == [] and set(again.cached) == {"space", "screen", "reduced", "design"}
    xr.testing.assert_identical(again["screen"], screen)
