"""Bad screening inputs raise clear errors naming the field and the allowed values, before any simulation; the group
designs embed each group's sample in full rows with the other parameters at the space's defaults."""

import numpy as np
import pytest

import spflow.plugins.forward.stage as forward_stage
from spflow.core.errors import ParameterError
from spflow.core.stage import StageContext
from spflow.plugins.design.parameter_space import ParameterSpace
from spflow.plugins.screening.groups import blocks_for, full_design
from spflow.plugins.screening.morris_screening import MorrisScreening
from spflow.plugins.screening.selected_space import SelectedSpace
from spflow.plugins.screening.sobol import sobol_indices, sobol_sample
from spflow.plugins.screening.sobol_screening import SobolScreening

CTX = StageContext("screening", verbose=False)


@pytest.fixture
def no_simulation(monkeypatch):
    calls = []
    monkeypatch.setattr(forward_stage, "simulate", lambda *a, **k: calls.append(a))
    yield calls
    assert calls == []


@pytest.fixture(scope="module")
def space():
    return ParameterSpace(names=["AD31", "HBNC70", "E2C"]).run(CTX)


@pytest.mark.parametrize("n", [0, 3, 100, 1000])
def test_sample_size_must_be_a_power_of_two(n):
    with pytest.raises(ParameterError, match="'samples'.*power of two|'samples' = 0 is outside"):
        SobolScreening(samples=n)
    with pytest.raises(ParameterError, match="power of two"):
        sobol_sample(["a"], np.zeros(1), np.ones(1), n)


@pytest.mark.parametrize("params, match", [
    ({"qois": ["recovery_final", "dp_max", "dp_max"]}, "'qois' must be a non-empty list without repeats"),
    ({"qois": ["dp"], "select_on": ["dp_max"]}, "'select_on'.*subset of qois"),
    ({"qois": ["npv"]}, "qois"),
    ({"mode": "each"}, "'mode'.*per_group"),
    ({"experiments": ["BCF9"]}, "experiments"),
    ({"cells": 2}, "cells"),
    ({"fixed": {"AD99": 1.0}}, "AD99"),
    ({"fixed": {"VIS2": -1.0}}, "VIS2"),
    ({"effects": {"surfactant_adsorption": 99.0}}, "surfactant_adsorption"),
    ({"effects": {"no_such_effect": 1.0}}, "no_such_effect"),
])
def test_bad_stage_parameters_raise_at_construction(params, match):
    with pytest.raises(ParameterError, match=match):
        SobolScreening(**params)
    with pytest.raises(ParameterError, match=match):
        MorrisScreening(**params)


def test_morris_levels_must_be_even():
    with pytest.raises(ParameterError, match="parameter levels = 5 must be an even integer"):
        MorrisScreening(levels=5)


@pytest.mark.parametrize("params, match", [
    ({"groups": {"a": ["AD31", "HBNC70"], "b": ["GAMHF"]}}, "'GAMHF' \\(group 'b'\\) is not in the input space"),
    ({"groups": {"a": ["AD31", "HBNC70"]}}, "\\['E2C'\\] are in no group"),
    ({"groups": {"a": ["AD31", "HBNC70", "E2C"], "b": ["E2C"]}}, "'E2C' is in groups 'a' and 'b'"),
    ({"groups": {"a": []}}, "group 'a' must be a non-empty list"),
    ({"fixed": {"E2C": 2.5}}, "'fixed' sets \\['E2C'\\], which the space varies"),
])
def test_space_dependent_errors_raise_before_any_simulation(space, no_simulation, params, match):
    with pytest.raises(ParameterError, match=match):
        SobolScreening(samples=4, cells=10, **params).run(CTX, space=space)


def test_design_outside_parameter_bounds_raises_before_any_simulation(no_simulation):
    # a space wider than the catalogue allows (AD31 >= 0): the forward stage rejects every row before simulating
    bad = ParameterSpace(names=["AD31"]).run(CTX).assign(lower=("param", [-1.0], {"units": "-"}))
    with pytest.raises(ParameterError, match="AD31"):
        SobolScreening(samples=4, cells=10).run(CTX, space=bad)


def test_analysis_rejects_wrong_row_counts_and_nan():
    with pytest.raises(ParameterError, match="multiple of 5 rows"):
        sobol_indices(np.ones(11), ["a", "b", "c"])
    with pytest.raises(ParameterError, match="finite"):
        sobol_indices(np.r_[np.ones(4), np.nan], ["a", "b", "c"])


def test_selected_space_refuses_an_empty_selection(space):
    empty = space.assign(selected=("param", np.zeros(3, bool)), group=("param", ["g"] * 3))
    empty.attrs["method"] = "sobol"
    with pytest.raises(ParameterError, match="selected no parameter"):
        SelectedSpace().run(CTX, screening=empty)


def test_group_blocks_vary_only_their_columns():
    names = ["a", "b", "c", "d"]
    groups = {"g1": ["a", "c"], "g2": ["b"], "g3": ["d"]}
    default = np.array([1.0, 2.0, 3.0, 4.0])
    blocks = blocks_for(names, groups, "per_group", lambda d: 3 * (d + 2))
    assert [b.rows for b in blocks] == [slice(0, 12), slice(12, 21), slice(21, 30)]
    samples = [np.full((12, 2), -1.0), np.full((9, 1), -2.0), np.full((9, 1), -3.0)]
    x = full_design(default, blocks, samples)
    expected = np.tile(default, (30, 1))
    expected[:12, [0, 2]] = -1.0
    expected[12:21, 1] = -2.0
    expected[21:, 3] = -3.0
    np.testing.assert_array_equal(x, expected)
    joint = blocks_for(names, groups, "joint", lambda d: 3 * (d + 2))
    assert len(joint) == 1 and joint[0].names == names and joint[0].rows == slice(0, 18)
