"""Pairing prediction columns with observations by (variable, experiment, PV) label."""

import numpy as np
import pytest
import xarray as xr

from spflow.core.errors import ParameterError
from spflow.plugins.calibration.aligned_data import align
from spflow.plugins.surrogates.outputs import stack_outputs


def _responses():
    pv = np.round(np.arange(5) * 0.1, 10)
    dp = np.arange(2 * 2 * 5, dtype=float).reshape(2, 2, 5)  # sample, experiment, pv
    dp[:, 1, 4] = np.nan  # experiment B ends earlier
    return xr.Dataset({"dp": (("sample", "experiment", "pv"), dp, {"units": "Pa"})},
                      coords={"sample": [0, 1], "experiment": ["A", "B"], "pv": pv})


def test_columns_pair_with_the_observation_at_the_same_label():
    y, index = stack_outputs(_responses(), ["dp"])
    obs_values = np.array([[10.0, 11, 12, 13, 14], [20, 21, np.nan, 23, np.nan]])
    obs = xr.Dataset({"dp": (("experiment", "pv"), obs_values)},
                     coords={"experiment": ["B", "A"], "pv": np.arange(5) * 0.1})  # other order on purpose
    aligned = align(index, obs, [("dp", "A"), ("dp", "B")])
    np.testing.assert_array_equal(aligned.observed("dp", "A"), [20, 21, 23])  # NaN observations dropped
    np.testing.assert_array_equal(aligned.observed("dp", "B"), [10, 11, 12, 13])  # B has no prediction at 0.4
    # the paired predictions are sample 1's dp of A at pv 0, 0.1, 0.3
    np.testing.assert_array_equal(aligned.predicted(y, "dp", "A")[1], _responses()["dp"].values[1, 0, [0, 1, 3]])


def test_unknown_pair_is_named():
    _, index = stack_outputs(_responses(), ["dp"])
    obs = xr.Dataset({"dp": (("experiment", "pv"), np.ones((1, 5)))}, coords={"experiment": ["A"],
                                                                            "pv": np.arange(5) * 0.1})
    with pytest.raises(ParameterError, match="'B'"):
        align(index, obs, [("dp", "B")])
