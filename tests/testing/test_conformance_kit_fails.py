"""The conformance kit must be able to fail: toy stages that each break one contract (mutate an input, draw unseeded
random numbers, miss their schema, swallow NaN, ...) fail exactly the check named for it, and a stage breaking several
gets one ConformanceError listing them all with the contract and the fix."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg
import xarray as xr

import spflow
from spflow.core.errors import SpflowError
from spflow.testing import STAGE_CHECKS, ConformanceError, check_stage

DATA = spflow.DatasetSchema(variables={"y": spflow.Variable(("x",), units="m", allow_nan=True)})


class Scale(spflow.Stage):
    """A conforming stage: y * factor, NaN propagated."""

    name = "toy_scale"
    inputs = {"data": DATA}
    output = spflow.DatasetSchema(variables={"y": spflow.Variable(("x",), units="m", allow_nan=True)})
    params = {"factor": spflow.Param(float, 2.0, bounds=(0, None)), "seed": spflow.Param(int, 0, bounds=(0, None))}

    def run(self, ctx, data):
        return xr.Dataset({"y": ("x", data["y"].values * self.params["factor"], {"units": "m"})},
                          coords={"x": data["x"].values})


def inputs():
    return {"data": xr.Dataset({"y": ("x", np.linspace(1.0, 2.0, 5), {"units": "m"})}, coords={"x": np.arange(5)})}


def failed(stage, **kwargs) -> set[str]:
    with pytest.raises(ConformanceError) as caught:
        check_stage(stage, inputs(), **kwargs)
    assert isinstance(caught.value, SpflowError)
    return set(caught.value.failed)


def test_a_conforming_stage_passes_every_check():
    report = check_stage(Scale, inputs(), params={"factor": 3.0})
    assert report.passed == list(STAGE_CHECKS)
    assert not report.skipped


def test_an_instance_is_checked_like_its_class():
    assert check_stage(Scale(factor=0.5), inputs()).passed == list(STAGE_CHECKS)


def test_mutating_an_input_fails_purity():
    class Mutates(Scale):
        def run(self, ctx, data):
            data["y"].values[0] = -1.0
            return super().run(ctx, data)

    assert failed(Mutates) == {"purity"}


def test_changing_an_input_attribute_fails_purity():
    class Relabels(Scale):
        def run(self, ctx, data):
            data["y"].attrs["units"] = "km"
            return super().run(ctx, data)

    assert failed(Relabels) == {"purity"}


def test_unseeded_randomness_fails_determinism():
    class Noisy(Scale):
        def run(self, ctx, data):
            out = super().run(ctx, data)
            return out + np.random.default_rng().normal(0.0, 1e-9, out["y"].shape)

    assert failed(Noisy) == {"determinism"}


def test_a_result_off_its_schema_fails_output_schema():
    class WrongDims(Scale):
        def run(self, ctx, data):
            return xr.Dataset({"y": (("x", "z"), data["y"].values[:, None], {"units": "m"})})

    assert failed(WrongDims) == {"output_schema"}


def test_a_variable_without_units_fails_output_units():
    class NoUnits(Scale):
        output = None

        def run(self, ctx, data):
            return super().run(ctx, data).assign(count=("x", np.arange(5)))

    assert failed(NoUnits) == {"output_units"}


def test_returning_the_input_itself_fails_runs():
    class Identity(Scale):
        def run(self, ctx, data):
            return data

    assert "runs" in failed(Identity)


def test_nan_turned_into_numbers_fails_nan_inputs():
    class Swallows(Scale):
        def run(self, ctx, data):
            out = super().run(ctx, data)
            return out.fillna(0.0)

    assert failed(Swallows) == {"nan_inputs"}


def test_a_raw_numpy_error_on_nan_fails_nan_inputs_and_a_parameter_error_passes():
    class Raw(Scale):
        def run(self, ctx, data):
            if np.isnan(data["y"].values).any():
                scipy.linalg.cholesky(np.diag(data["y"].values))  # scipy's ValueError, not a spflow error
            return super().run(ctx, data)

    class Clear(Scale):
        def run(self, ctx, data):
            if np.isnan(data["y"].values).any():
                raise spflow.ParameterError("stage 'toy_scale' port 'data' variable 'y': NaN is not allowed")
            return super().run(ctx, data)

    assert failed(Raw) == {"nan_inputs"}
    assert "nan_inputs" in check_stage(Clear, inputs()).passed


def test_nan_documented_as_missing_data_passes_when_the_port_says_so():
    class SkipsMissing(Scale):
        def run(self, ctx, data):
            return super().run(ctx, data.fillna(float(data["y"].max())))

    assert failed(SkipsMissing) == {"nan_inputs"}
    assert "nan_inputs" in check_stage(SkipsMissing, inputs(), nan_as_missing=["data"]).passed


def test_an_attribute_netcdf_cannot_hold_fails_cache_round_trip():
    class BoolAttr(Scale):
        def run(self, ctx, data):
            out = super().run(ctx, data)
            out.attrs["converged"] = True
            return out

    assert failed(BoolAttr) == {"cache_round_trip"}


def test_params_changed_by_the_constructor_fail_params():
    class Rewrites(Scale):
        def __init__(self, **params):
            super().__init__(**params)
            self.params = {**self.params, "factor": 1.0}

    assert failed(Rewrites, params={"factor": 3.0}) == {"params"}


def test_a_default_outside_its_own_bounds_fails_declaration():
    class BadDefault(Scale):
        params = {"factor": spflow.Param(float, -1.0, bounds=(0, None)), "seed": spflow.Param(int, 0)}

    with pytest.raises(ConformanceError, match="default of param 'factor' fails its own declaration") as caught:
        check_stage(BadDefault, inputs(), params={"factor": 1.0})
    assert caught.value.failed == ["declaration"]


def test_a_refused_constructor_argument_fails_construct_naming_the_error():
    with pytest.raises(ConformanceError, match="refused the params") as caught:
        check_stage(Scale, inputs(), params={"factor": -1.0})
    assert caught.value.failed == ["construct"]


def test_inputs_off_the_port_schema_are_reported_and_the_runs_skipped():
    bad = {"data": xr.Dataset({"y": ("x", np.ones(3))})}  # no units attr
    with pytest.raises(ConformanceError) as caught:
        check_stage(Scale, bad)
    assert caught.value.failed == ["inputs"]
    assert caught.value.report.skipped["runs"] == "needs inputs to pass first"


def test_several_broken_contracts_come_in_one_error_with_contract_and_fix():
    class Everything(Scale):
        def run(self, ctx, data):
            data["y"].values[:] += np.random.default_rng().normal(size=data["y"].size)
            return xr.Dataset({"y": ("x", data["y"].values.copy())})  # no units attr: off the schema

    with pytest.raises(ConformanceError) as caught:
        check_stage(Everything, inputs())
    assert {"purity", "determinism", "output_schema"} <= set(caught.value.failed)
    message = str(caught.value)
    for name in ("purity", "determinism", "output_schema"):
        check = STAGE_CHECKS[name]
        assert f"- {name}: {check.contract}" in message and f"fix: {check.fix}" in message


def test_filling_a_nan_input_in_place_fails_nan_inputs():
    class FillsInPlace(Scale):
        def run(self, ctx, data):
            values = data["y"].values
            values[np.isnan(values)] = -1.0  # writes into the input only when it holds a NaN
            return super().run(ctx, data)

    with pytest.raises(ConformanceError, match="run\\(\\) changed that input") as caught:
        check_stage(FillsInPlace, inputs())
    assert caught.value.failed == ["nan_inputs"]
