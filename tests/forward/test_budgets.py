"""Step and wall-time budgets of the 1-D forward model: exceeding either raises SimulationError naming the PV, the
cell and the state; the defaults follow the documented formula; bad budgets are rejected before any work."""

import math
import pickle

import numpy as np
import pytest

from spflow.core.errors import ParameterError
from spflow.plugins.forward import state_layout as L
from spflow.plugins.forward.errors import SimulationError
from spflow.plugins.forward.kernel import run_kernel
from spflow.plugins.forward.run_arguments import validate_run
from spflow.plugins.forward.simulate import kernel_arguments, simulate

WATER = [{"pv": 0.5, "salinity_ppm": 9400.0}]


def test_default_budgets_follow_the_documented_formula():
    ds = simulate("BCF1", cells=40)
    # BCF1: 1.45 + 0.5 + 1.01 + 1.27 = 4.23 PV (thesis Table 2.5); 50 x ceil(4.23 * 40 * 4 / 0.5)
    assert ds.attrs["max_steps"] == 50 * math.ceil(4.23 * 40 * 4 / 0.5 - 1e-9) == 50 * 1354
    assert ds.attrs["max_wall_s"] == 600.0
    assert ds.attrs["n_steps"] < ds.attrs["max_steps"]


def test_step_budget_is_exact_and_names_pv_cell_and_state():
    # the explicit scheme: the budgeted default takes longer steps past half a tight budget (test_budgeted_capillary)
    full = simulate(WATER, cells=20, capillary="explicit")
    steps = full.attrs["n_steps"]
    again = simulate(WATER, cells=20, max_steps=steps, capillary="explicit")  # exactly enough
    np.testing.assert_array_equal(again["recovery"].values, full["recovery"].values)
    with pytest.raises(SimulationError) as info:
        simulate(WATER, cells=20, max_steps=steps - 1, capillary="explicit")
    err = info.value
    assert err.code == L.ERR_STEPS
    assert 0.0 < err.pv < 0.5 and 0 <= err.cell < 20
    msg = str(err)
    assert f"max_steps = {steps - 1}" in msg and "step budget" in msg and f"cell {err.cell} of 20" in msg
    assert "water=" in msg and "S_aqueous=" in msg
    # the state is that of a cell of the waterflood: water + oil fill the pore volume (no surfactant injected)
    assert err.state["water"] + err.state["oil"] == pytest.approx(1.0, abs=1e-9)


def test_step_budget_of_one_step_stops_after_one_step():
    with pytest.raises(SimulationError, match=r"max_steps = 1\]") as info:
        simulate(WATER, cells=20, max_steps=1)
    # one step from t = 0: the ramp's first step is cfl * dx / 16 = 0.5 / 20 / 16 PV (kernel.RAMP_SPEED)
    assert info.value.pv == pytest.approx(0.5 / 20 / 16, rel=1e-12)


def test_wall_flag_stops_the_kernel_before_the_next_step():
    sched, resolved, strengths, _, cells, pv_step, prof, cfl = validate_run(WATER, None, 20, None, "tvd", 0.01,
                                                                             None, 0.5)
    prm, end_pv, inj, flow, out_pv = kernel_arguments(sched, resolved, strengths, pv_step)
    stop = np.ones(1, dtype=np.int64)
    status, info, steps, *_ = run_kernel(prm, end_pv, inj, flow, out_pv, prof, cells, True, cfl, 10**9, stop)
    assert status == L.ERR_WALL and steps == 0 and info[0] == 0.0
    err = SimulationError(status, info, cells, "max_wall_s = 1 s")
    assert "wall-time budget" in str(err) and "max_wall_s = 1 s" in str(err) and "0 PV" in str(err)


def test_wall_time_budget_stops_a_long_run():
    # 3000 cells of BCF1 need ~ 60 000 steps (seconds of CPU); a 20 ms budget stops it early
    with pytest.raises(SimulationError, match=r"wall-time budget.*max_wall_s = 0.02 s") as info:
        simulate("BCF1", cells=3000, max_wall_s=0.02)
    assert info.value.code == L.ERR_WALL and info.value.pv < 4.23


def test_simulation_error_survives_pickling():
    with pytest.raises(SimulationError) as info:
        simulate(WATER, cells=20, max_steps=3)
    back = pickle.loads(pickle.dumps(info.value))
    assert type(back) is SimulationError and str(back) == str(info.value) and back.cell == info.value.cell


@pytest.mark.parametrize("kwargs,match", [
    ({"max_steps": 0}, r"max_steps must be an integer in \[1, "),
    ({"max_steps": 10.0}, r"max_steps must be an integer"),
    ({"max_steps": True}, r"max_steps must be an integer"),
    ({"max_wall_s": 0.0}, r"max_wall_s must be a number of seconds in \(0, inf\)"),
    ({"max_wall_s": math.nan}, r"max_wall_s"),
    ({"max_wall_s": "10"}, r"max_wall_s"),
    ({"max_steps": 10, "cells": (10, 2)}, r"1-D runs only"),
])
def test_bad_budgets_are_rejected(kwargs, match):
    with pytest.raises(ParameterError, match=match):
        simulate(WATER, **{"cells": 20, **kwargs})
