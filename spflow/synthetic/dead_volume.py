"""Dead volume of the outlet lines: the collector sees the core's effluent ``v_dead`` pore volumes late.

Effluent signals are interval averages: ``values[k]`` is the mean over the injected-PV interval
``(pv[k-1], pv[k]]`` (``values[0]`` is the value at ``pv = 0``), the convention of
:func:`spflow.plugins.forward.simulate.simulate`. With an outlet line of volume ``v_dead`` (PV) that is full of
``fill`` fluid at the start, the collector receives ``fill`` during ``(0, v_dead]`` and the core's effluent of
``(pv[k-1], pv[k]]`` during ``(pv[k-1] + v_dead, pv[k] + v_dead]``: a pure translation in PV (plug flow in the
line; the line's own dispersion is neglected).
"""

from __future__ import annotations

import numpy as np

__all__ = ["delay"]


def delay(pv: np.ndarray, values: np.ndarray, v_dead: float, fill: float):
    """The interval signal seen after a line of ``v_dead`` PV initially full of ``fill``.

    Returns ``(pv_out, values_out)`` with the same interval convention; the grid is ``pv + v_dead`` preceded by
    the line-flush interval ``(0, v_dead]`` and extends ``v_dead`` past ``pv[-1]``.
    """
    if not (np.isfinite(v_dead) and v_dead >= 0.0):
        raise ValueError(f"dead volume v_dead = {v_dead!r} PV is out of range; allowed [0, inf) PV")
    pv = np.asarray(pv, dtype=np.float64)
    values = np.asarray(values, dtype=np.float64)
    if v_dead == 0.0:
        return pv.copy(), values.copy()
    pv_out = np.concatenate(([0.0, v_dead], pv[1:] + v_dead))
    values_out = np.concatenate(([fill, fill], values[1:]))
    return pv_out, values_out
