"""Run budgets of the 1-D forward model: a step budget and a wall-time budget, so that no run goes on without end.

Step budget (default ``max_steps``): ``STEP_BUDGET_FACTOR`` times the steps a run of that schedule and grid
normally needs, estimated from the CFL condition with a generous wave-speed bound ``REFERENCE_SPEED`` (PV units,
``dt = cfl dx / speed``):

    expected = ceil(total_pv * cells * REFERENCE_SPEED / cfl),    max_steps = STEP_BUDGET_FACTOR * expected.

Wall-time budget (default ``max_wall_s``): ``DEFAULT_MAX_WALL_S`` seconds. numba has no clock, so the compiled
kernel polls a flag (``stop[0]``) before every step; a watchdog thread (:func:`wall_clock_flag`) sets it when the
budget has passed (the kernel releases the GIL, so the watchdog runs while it computes).
"""

from __future__ import annotations

import math
import threading
from contextlib import contextmanager

import numpy as np

from spflow.core.errors import ParameterError

__all__ = ["REFERENCE_SPEED", "STEP_BUDGET_FACTOR", "DEFAULT_MAX_WALL_S", "expected_steps", "resolve_budgets",
           "wall_clock_flag"]

#: wave-speed bound (PV units) of the step estimate: above the median largest speed of in-bounds runs
REFERENCE_SPEED = 4.0
#: the default step budget is this many times the expected steps
STEP_BUDGET_FACTOR = 50
#: default wall-time budget of one run (s)
DEFAULT_MAX_WALL_S = 600.0
_MAX_STEPS_LIMIT = 2**62


def expected_steps(total_pv: float, cells: int, cfl: float) -> int:
    """The steps a run of ``total_pv`` pore volumes on ``cells`` cells normally needs at Courant number ``cfl``."""
    # rounded to 1e-9 first: 4.23 * 100 * 4 / 0.5 is 3384.0000000000005 in floating point
    return int(math.ceil(round(total_pv * cells * REFERENCE_SPEED / cfl, 9)))


def resolve_budgets(max_steps, max_wall_s, total_pv: float, cells: int, cfl: float) -> tuple[int, float]:
    """``(max_steps, max_wall_s)``: the defaults where ``None``, else the validated values (a positive integer and a
    positive finite number of seconds)."""
    if max_steps is None:
        max_steps = STEP_BUDGET_FACTOR * expected_steps(total_pv, cells, cfl)
    elif isinstance(max_steps, bool) or not isinstance(max_steps, (int, np.integer)) or not (
            1 <= max_steps <= _MAX_STEPS_LIMIT):
        raise ParameterError(f"max_steps must be an integer in [1, {_MAX_STEPS_LIMIT}] (or None: "
                             f"{STEP_BUDGET_FACTOR} x the expected steps), got {max_steps!r}")
    if max_wall_s is None:
        max_wall_s = DEFAULT_MAX_WALL_S
    else:
        ok = not isinstance(max_wall_s, bool) and isinstance(max_wall_s, (int, float, np.integer, np.floating))
        if not ok or not (math.isfinite(max_wall_s) and max_wall_s > 0.0):
            raise ParameterError(f"max_wall_s must be a number of seconds in (0, inf) (or None: "
                                 f"{DEFAULT_MAX_WALL_S:g} s), got {max_wall_s!r}")
    return int(max_steps), float(max_wall_s)


@contextmanager
def wall_clock_flag(seconds: float):
    """A flag array ``stop[1]`` (int64) that a daemon timer sets to 1 after ``seconds``; the timer is cancelled on
    exit."""
    stop = np.zeros(1, dtype=np.int64)
    timer = threading.Timer(seconds, stop.fill, (1,))
    timer.daemon = True
    timer.start()
    try:
        yield stop
    finally:
        timer.cancel()
