"""Base-model specification: unit-box transforms, tied parameters, validation errors naming the field."""

import numpy as np
import pytest

from spflow.core.errors import ParameterError
from spflow.plugins.gap.base_model import TABLE_3_2_BASE, BaseModel, unit_to_value, value_to_unit
from spflow.plugins.gap.catalogue import PHYSICAL_RANGES, candidates_for


def test_transforms_round_trip_linear_and_log():
    lo, hi, log = np.array([1.0, 1e-3]), np.array([3.0, 10.0]), np.array([False, True])
    u = np.array([0.25, 0.5])
    x = unit_to_value(u, lo, hi, log)
    np.testing.assert_allclose(x, [1.5, np.sqrt(1e-3 * 10.0)])
    np.testing.assert_allclose(value_to_unit(x, lo, hi, log), u)


def test_tied_parameters_and_defaults():
    base = BaseModel.from_mapping(TABLE_3_2_BASE)
    assert base.labels[-3:] == ["n_high", "n_low", "ALPHAL1"]
    params = base.forward_params(base.values(np.full(9, 0.5)))
    assert params["E1C"] == params["E2C"] == params["E3C"] == pytest.approx(2.25)
    assert params["GAMHF"] == pytest.approx(77.5)
    # the forward model's defaults (Table 2.4) as a unit-box point: ALPHAV2 = 2 of [0, 3]
    assert base.default_unit()[0] == pytest.approx(2.0 / 3.0)
    assert base.effects["capillary_pressure"] == 0.0 and base.effects["dispersion"] == 1.0


@pytest.mark.parametrize("config, message", [
    ({"parameters": {}}, "at least one calibrated parameter"),
    ({"parameters": {"ALPHAV2": [0, 3]}, "cell": 3}, r"unknown key\(s\) \['cell'\]"),
    ({"parameters": {"NOPE": [0, 1]}}, "unknown forward-model parameter 'NOPE'"),
    ({"parameters": {"ALPHAV2": [3, 1]}}, "lower < upper"),
    ({"parameters": {"PORO": [0.1, 0.9]}}, r"leaves the bounds of PORO \[0.01, 0.6\]"),
    ({"parameters": {"AD31": {"range": [0, 1], "scale": "log"}}}, "log scale needs lower > 0"),
    ({"parameters": {"a": {"names": ["E1C"], "range": [1.5, 3]}, "b": {"names": ["E1C"], "range": [1.5, 3]}}},
     "set by more than one"),
    ({"parameters": {"AD31": [0, 2]}, "fixed": {"AD31": 0.3}}, "both \\[fixed\\] and calibrated"),
    ({"parameters": {"AD31": [0, 2]}, "cells": 2}, r"'cells' must be an integer in \[4, 2000\]"),
    ({"parameters": {"AD31": [0, 2]}, "scheme": "weno"}, r"'scheme' must be one of \['tvd', 'upwind'\]"),
    ({"parameters": {"AD31": [0, 2]}, "pv_step": 0.5}, r"'pv_step' must be in \[0.0001, 0.1\] PV"),
    ({"parameters": {"AD31": [0, 2]}, "pv_step": "fine"}, "'pv_step' must be a finite number"),
    ({"parameters": {"AD31": [0, 2]}, "effects": {"dispersion": 99}}, r"allowed \[0, 10\]"),
    ({"parameters": {"AD31": [0, 2]}, "schedules": {"x": "BCF9"}}, "unknown schedule name 'BCF9'"),
])
def test_bad_base_models_raise_naming_the_field(config, message):
    with pytest.raises(ParameterError, match=message):
        BaseModel.from_mapping(config)


def test_candidates_off_and_on_in_the_base():
    cands = {c.name: c for c in candidates_for(None, BaseModel.from_mapping(TABLE_3_2_BASE).effects)}
    pc = cands["capillary_pressure"]  # off in the base: a missing mechanism
    assert pc.base == 0.0 and pc.levels == PHYSICAL_RANGES["capillary_pressure"][3]
    assert pc.lower < pc.physical[0] and pc.upper > pc.physical[1]
    assert pc.value(pc.unit(0.7)) == pytest.approx(0.7)
    disp = cands["dispersion"]  # on in the base: a mis-specified strength, tested at half and double
    assert disp.levels == (0.5, 2.0) and disp.lower <= 1.0 <= disp.upper
    ipv = cands["inaccessible_pore_volume"]  # its upper bound is the base value: only the weaker side
    assert ipv.levels == (0.5,)
    assert pc.is_physical(1.0) and not pc.is_physical(0.05)
    with pytest.raises(ParameterError, match="unknown candidate effect 'gravity'"):
        candidates_for(["gravity"], {})
    with pytest.raises(ParameterError, match="must be distinct"):
        candidates_for(["dispersion", "dispersion"], {})


def test_physical_rule_with_a_tolerance_in_posterior_sd():
    """A strength outside the physical range counts as physical when it lies within ``tolerance`` (unit-box
    coordinates of the search range) of it; distances computed here by hand from the search range."""
    cands = {c.name: c for c in candidates_for(None, BaseModel.from_mapping(TABLE_3_2_BASE).effects)}
    sal = cands["polymer_salinity"]  # linear search range, physical 0.3-1.5
    span = sal.upper - sal.lower
    over = 1.5 + 0.1 * span  # 0.1 of the search range above the physical upper bound
    assert not sal.is_physical(over)
    assert not sal.is_physical(over, tolerance=0.09)
    assert sal.is_physical(over, tolerance=0.11)
    under = 0.3 - 0.05 * span
    assert sal.is_physical(under, tolerance=0.06) and not sal.is_physical(under, tolerance=0.04)
    pc = cands["capillary_pressure"]  # log search range, physical 0.1-4
    weak = 0.05  # log distance to 0.1 in units of the search range's log span
    dist = np.log(0.1 / weak) / np.log(pc.upper / pc.lower)
    assert pc.is_physical(weak, tolerance=dist * 1.01) and not pc.is_physical(weak, tolerance=dist * 0.99)
    assert pc.is_physical(1.0, tolerance=0.0)
