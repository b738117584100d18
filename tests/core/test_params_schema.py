"""Parameter validation and schema errors name the stage, the field and the allowed range."""

import numpy as np
import pytest
import xarray as xr

from spflow import DatasetSchema, Param, ParameterError, SchemaError, Variable
from spflow.core.params import validate_params

SPECS = {
    "n": Param(int, 10, bounds=(1, 100)),
    "rate": Param(float, 0.5, bounds=(0.0, 1.0), unit="ml/min"),
    "method": Param(str, "lhs", choices=["lhs", "sobol"]),
    "names": Param(list, ["a"]),
    "seed": Param(int),
}


def test_defaults_filled_and_types_normalised():
    out = validate_params("design", SPECS, {"seed": 3, "rate": 1, "n": np.int64(4)})
    assert out == {"n": 4, "rate": 1.0, "method": "lhs", "names": ["a"], "seed": 3}
    assert isinstance(out["rate"], float) and isinstance(out["n"], int)


@pytest.mark.parametrize(
    "given, message",
    [
        ({"seed": 1, "n": 0}, "stage 'design' parameter 'n' = 0 is outside the allowed range [1, 100]"),
        ({"seed": 1, "rate": 2.0}, "parameter 'rate' = 2.0 is outside the allowed range [0.0, 1.0] ml/min"),
        ({"seed": 1, "rate": float("nan")}, "parameter 'rate' must be finite"),
        ({"seed": 1, "n": 2.5}, "parameter 'n' must be an integer"),
        ({"seed": 1, "n": "3"}, "parameter 'n' must be a int"),
        ({"seed": 1, "method": "grid"}, "parameter 'method' = 'grid' is not allowed; allowed: one of 'lhs', 'sobol'"),
        ({"seed": 1, "nn": 3}, "stage 'design' has no parameter 'nn'; did you mean n"),
        ({}, "stage 'design' parameter 'seed' is required"),
        ({"seed": True}, "parameter 'seed' must be a int"),
    ],
)
def test_bad_params_name_stage_param_and_range(given, message):
    with pytest.raises(ParameterError) as info:
        validate_params("design", SPECS, given)
    assert message in str(info.value)


SCHEMA = DatasetSchema(
    dims=("sample", "pv"),
    variables={"dp": Variable(("sample", "pv"), units="Pa"), "flag": Variable(("sample",), kind="i", required=False)},
)


def _good():
    return xr.Dataset(
        {"dp": (("sample", "pv"), np.ones((2, 3)), {"units": "Pa"})}, coords={"pv": [0.0, 0.1, 0.2]}
    )


def test_schema_accepts_conforming_dataset():
    SCHEMA.validate(_good(), stage="forward", port="responses")


@pytest.mark.parametrize(
    "mutate, message",
    [
        (lambda ds: ds.rename({"sample": "s"}), "expected dims ['sample', 'pv'], found ['s', 'pv']"),
        (lambda ds: ds.assign(dp=ds.dp.T), "variable 'dp': expected dims ('sample', 'pv'), found ('pv', 'sample')"),
        (lambda ds: ds.assign(dp=ds.dp.astype(int)), "variable 'dp': expected dtype float, found int64"),
        (lambda ds: ds.assign(flag=("sample", [0.5, 1.0])), "variable 'flag': expected dtype integer, found float64"),
        (lambda ds: ds.drop_vars("dp").assign(q=(("sample", "pv"), np.ones((2, 3)))), "variable 'dp': expected a variable"),
    ],
)
def test_schema_violations_name_stage_port_variable_expected_found(mutate, message):
    with pytest.raises(SchemaError) as info:
        SCHEMA.validate(mutate(_good()), stage="forward", port="responses")
    assert str(info.value).startswith("stage 'forward' port 'responses'")
    assert message in str(info.value)


def test_schema_requires_units_attr():
    ds = _good()
    ds["dp"].attrs = {}
    with pytest.raises(SchemaError, match="variable 'dp': expected attrs\\['units'\\] = 'Pa', found no units"):
        SCHEMA.validate(ds, stage="forward", port="responses")


def test_a_unit_in_catalogue_notation_matches_its_udunits_form_and_nothing_else():
    # the executor stores every result with its units in UDUNITS form (cf_metadata.note_units): a schema declaring
    # "PV" or "cP" must accept what it stored ("1", "cpoise") -- on a cache hit too -- and still reject other units
    schema = DatasetSchema(("sample",), {"pv_front": Variable(("sample",), units="PV"),
                                         "mu": Variable(("sample",), units="cP")})
    stored = xr.Dataset({"pv_front": ("sample", [0.4, 0.5], {"units": "1"}),
                         "mu": ("sample", [1.0, 2.0], {"units": "cpoise"})})
    schema.validate(stored, stage="plugin", port="output")
    with pytest.raises(SchemaError, match="expected units 'cP', found 'Pa s'"):
        schema.validate(stored.assign(mu=stored.mu.assign_attrs(units="Pa s")), stage="plugin", port="output")
