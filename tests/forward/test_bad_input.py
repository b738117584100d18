"""Every class of bad input raises a ValueError naming the field and its allowed range, before any work."""

import math

import numpy as np
import pytest

from spflow.core.errors import PluginError
from spflow.plugins.forward import state_layout
from spflow.plugins.forward.effects import BUILTIN_EFFECTS, Effect, EffectRegistry
from spflow.plugins.forward.errors import SimulationError
from spflow.plugins.forward.parameters import parameter_table, resolve_params
from spflow.plugins.forward.schedule import Schedule, Slug, as_schedule
from spflow.plugins.forward.simulate import simulate

WATER = [{"pv": 0.2, "salinity_ppm": 9400.0}]


def _raises(match, func, *args, **kwargs):
    with pytest.raises(ValueError, match=match) as info:
        func(*args, **kwargs)
    return str(info.value)


# --- parameters -----------------------------------------------------------------------------------------------
def test_unknown_parameter_suggests_close_match():
    msg = _raises("AP11", resolve_params, {"AP11": 1.0})
    assert "did you mean" in msg and "AP1" in msg


@pytest.mark.parametrize("name,value", [("PORO", 0.9), ("PORO", 0.0), ("HBNC70", -0.1), ("GAMHF", 0.0),
                                        ("CRK", 2.0), ("ALPHAL1", 5.0), ("E1WC", 0.2)])
def test_out_of_range_parameter_names_field_and_range(name, value):
    msg = _raises(name, resolve_params, {name: value})
    assert "out of range" in msg and "[" in msg and "]" in msg


@pytest.mark.parametrize("name,value", [("VIS1", 0.0118), ("VIS1", 327.0), ("VIS2", 0.0117)])
def test_unphysical_fluid_viscosity_names_field_and_physical_range(name, value):
    """Issue-22 stress draws: a 0.0118 cP and a 327 cP "brine", a 0.0117 cP (gas-like) "oil"."""
    msg = _raises(name, resolve_params, {name: value})
    assert {"VIS1": "[0.1, 10] cP", "VIS2": "[0.1, 100000] cP"}[name] in msg


@pytest.mark.parametrize("name,value", [("VIS1", 1.7912), ("VIS1", 0.1346), ("VIS1", 3.0), ("VIS2", 0.30)])
def test_physical_fluid_viscosities_are_accepted(name, value):
    """Handbook fluids inside the bounds: water at 0.01 and 200 C (IAPWS 2008), a 4 mol/kg CaCl2 brine at 30 C
    (~3 mPa s), n-hexane at 25 C (0.30 mPa s)."""
    assert resolve_params({name: value})[name] == value


@pytest.mark.parametrize("value", [math.nan, math.inf, -math.inf])
def test_non_finite_parameter(value):
    msg = _raises("AD31", resolve_params, {"AD31": value})
    assert "finite" in msg and "[0, 10]" in msg


@pytest.mark.parametrize("value", ["abc", None, True, [1.0]])
def test_non_numeric_parameter(value):
    _raises("VIS2.*number", resolve_params, {"VIS2": value})


def test_integer_flag():
    _raises("IGAMHF.*integer", resolve_params, {"IGAMHF": 0.5})


def test_params_must_be_a_mapping():
    _raises("mapping", resolve_params, [("AP1", 1.0)])


@pytest.mark.parametrize("params,match", [
    ({"CSEL": 0.4, "CSEU": 0.3}, "CSEL.*CSEU"),
    ({"S1RWC": 0.5, "S2RWC": 0.5}, "sum to < 1"),
    ({"S1RC": 0.3}, "S1RC.*S1RWC"),
    ({"BETA6": 2.0, "F6S": 0.6}, "BETA6"),
])
def test_cross_parameter_violations(params, match):
    _raises(match, resolve_params, params)


def test_fixed_plait_points_explain_range():
    msg = _raises("C2PRC", resolve_params, {"C2PRC": 0.5})
    assert "[1, 1]" in msg


def test_parameter_table_is_complete_and_consistent():
    table = parameter_table()
    names = [row["name"] for row in table]
    assert len(names) == len(set(names))
    for row in table:
        assert row["lower"] <= row["default"] <= row["upper"], row["name"]
        assert row["unit"] and row["description"] and row["submodel"]
    # Table 3.2 prior ranges lie inside the bounds
    rows = {row["name"]: row for row in table}
    for name, lo, hi in [("ALPHAV2", 0, 3), ("HBNC70", 0.02, 0.05), ("HBNC71", 0.01, 0.02), ("AD31", 0, 2),
                         ("GAMHF", 55, 100), ("CRK", 0.05, 0.1), ("E1WC", 1.5, 3), ("E1C", 1.5, 3),
                         ("ALPHAL1", 0.008, 0.012)]:
        assert rows[name]["lower"] <= lo and hi <= rows[name]["upper"], name
    assert rows["ALPHAL1"]["unit"] == "ft"


# --- schedules --------------------------------------------------------------------------------------------------
@pytest.mark.parametrize("slugs,match", [
    ([], "empty"),
    ([{"pv": -0.1, "salinity_ppm": 9400.0}], r"slug 0.*'pv'.*\(0, inf\)"),
    ([{"pv": 0.0, "salinity_ppm": 9400.0}], r"slug 0.*'pv'"),
    ([{"pv": 0.3, "salinity_ppm": 9400.0}, {"pv": 0.2, "salinity_ppm": -5.0}], r"slug 1.*'salinity_ppm'.*\[0, "),
    ([{"pv": 0.3, "salinity_ppm": 9400.0, "polymer_ppm": -1.0}], r"'polymer_ppm'.*\[0, "),
    ([{"pv": 0.3, "salinity_ppm": 9400.0, "surfactant_ppm": math.nan}], r"'surfactant_ppm'.*finite"),
    ([{"pv": math.inf, "salinity_ppm": 9400.0}], r"'pv'.*finite"),
    ([{"pv": 0.3}], "missing field 'salinity_ppm'"),
    ([{"pv": 0.3, "salinity_ppm": 1.0, "tracer": 1.0}], "unknown field"),
    ("BCF9", "unknown schedule name.*BCF1"),
    (42, "schedule must be"),
])
def test_bad_schedules(slugs, match):
    _raises(match, as_schedule, slugs)
    _raises(match, simulate, slugs)


def test_schedule_and_slug_objects_validate():
    _raises(r"slug 0 \('P'\).*'pv'", Schedule, (Slug("P", -1.0, 9400.0),), "bad")
    _raises("empty", Schedule, (), "none")


# --- effects ----------------------------------------------------------------------------------------------------
def test_unknown_effect_lists_known_ones():
    msg = _raises("unknown effect 'shear_thining'", simulate, WATER, effects={"shear_thining": 1.0})
    assert "shear_thinning" in msg and "dispersion" in msg


@pytest.mark.parametrize("value", [-0.5, 1.5, math.nan, "x"])
def test_effect_strength_out_of_range(value):
    _raises(r"shear_thinning.*\[0, 1\]", simulate, WATER, effects={"shear_thinning": value})


def test_registry_rejects_duplicates_and_resolves_defaults():
    reg = EffectRegistry(BUILTIN_EFFECTS)
    with pytest.raises(PluginError, match="already registered"):
        reg.register(BUILTIN_EFFECTS[0])
    strengths = reg.resolve(None)
    assert strengths["capillary_pressure"] == 0.0 and strengths["kinetic_adsorption"] == 0.0
    assert strengths["dispersion"] == 1.0
    with pytest.raises(PluginError):
        Effect("bad name", "x", 0.5)
    with pytest.raises(PluginError):
        Effect("too_strong", "x", 2.0, 0.0, 1.0)


# --- simulate() arguments ---------------------------------------------------------------------------------------
@pytest.mark.parametrize("kwargs,match", [
    ({"cells": 2}, r"cells.*\[3, 20000\]"),
    ({"cells": 10.5}, "cells"),
    ({"scheme": "weno"}, "scheme.*tvd.*upwind|scheme.*upwind.*tvd"),
    ({"pv_step": 0.0}, r"pv_step.*\(0, 0.2\]"),
    ({"pv_step": 1.0}, r"pv_step.*\(0, 0.2\]"),
    ({"cfl": 0.7}, r"cfl.*\(0, 0.5\]"),
    ({"cfl": 1.2, "scheme": "upwind"}, r"cfl.*\(0, 1\]"),
    ({"profiles_at": [0.1, 0.5]}, r"profiles_at\[1\].*\[0, 0.2"),
    ({"profiles_at": [math.nan]}, r"profiles_at\[0\]"),
    ({"params": {"PERM": -1.0}}, r"PERM.*\[0.1, 100000\] mD"),
])
def test_bad_simulate_arguments(kwargs, match):
    _raises(match, simulate, WATER, **kwargs)


def test_simulation_error_names_time_cell_and_state():
    info = np.array([1.234, 7, 0.3, 0.7, 0.0, 0.0, 0.05, 0.001, 0.31, 0.69, 0.0, 1e-9])
    err = SimulationError(state_layout.ERR_COLLAPSE, info, 20)
    msg = str(err)
    assert "1.234 PV" in msg and "cell 7 of 20" in msg and "time-step collapse" in msg
    assert "water=0.3" in msg and "S_oleic=0.69" in msg
    assert err.pv == 1.234 and err.cell == 7 and err.state["oil"] == 0.7


# --- issue 22 item 8: strings are not numbers, SWI below the residual water saturation ---------------------------
@pytest.mark.parametrize("value", ["0.5", b"0.5", "nan"])
def test_string_parameter_is_not_coerced(value):
    msg = _raises(r"parameter AD31 must be a number", simulate, "BCF1", {"AD31": value})
    assert "[0, 10]" in msg


def test_string_schedule_field_is_not_coerced():
    _raises(r"slug 0 \('slug0'\): field 'pv' must be a number in \(0, inf\)", simulate,
            [{"pv": "0.5", "salinity_ppm": 9400.0}])


def test_swi_below_residual_water_saturation_names_both_and_the_range():
    msg = _raises(r"SWI = 0.1 .*below S1RWC = 0.25", resolve_params, {"SWI": 0.1, "S1RWC": 0.25})
    assert "allowed SWI in [S1RWC, 1] = [0.25, 1]" in msg
    assert resolve_params({"SWI": 0.25, "S1RWC": 0.25})["SWI"] == 0.25  # equal is the usual connate state
