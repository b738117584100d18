"""The pressure drop with capillary pressure on is as smooth in a parameter as without it.

The reference is the same flood with Pc off: a pressure drop that moves by percents when a Corey exponent moves by
1e-4 is a discretisation artefact, not physics (the phase-pressure form integrated cell by cell added the jump of
``f_c (Pc_{i+1} - Pc_i)`` at the capillary front's faces; the global pressure has no such term).
"""

import numpy as np
import pytest

from spflow import simulate

WATERFLOOD = [{"pv": 2.0, "salinity_ppm": 20000, "surfactant_ppm": 0, "polymer_ppm": 0}]
POLYMER_FLOOD = [{"pv": 0.5, "salinity_ppm": 20000, "surfactant_ppm": 0, "polymer_ppm": 0},
                 {"pv": 1.0, "salinity_ppm": 20000, "surfactant_ppm": 0, "polymer_ppm": 1000},
                 {"pv": 1.0, "salinity_ppm": 20000, "surfactant_ppm": 0, "polymer_ppm": 0}]


def _roughness(schedule, effects, n=21, h=2e-3):
    """Largest second difference of dp / max dp over ``n`` water Corey exponents within +-h of 2."""
    rows = []
    for t in np.linspace(-1.0, 1.0, n):
        ds = simulate(schedule, {"E1WC": 2.0 * (1.0 + h * t)}, cells=60, pv_step=0.05, effects=effects)
        dp = ds["dp"].values
        rows.append(dp / np.abs(dp).max())
    return float(np.abs(np.diff(np.array(rows), 2, axis=0)).max())


@pytest.mark.parametrize("schedule, factor", [(WATERFLOOD, 2.0), (POLYMER_FLOOD, 10.0)],
                         ids=["waterflood", "polymer"])
def test_pressure_drop_with_pc_is_as_smooth_as_without(schedule, factor):
    # measured: waterflood 1.1e-6 with Pc against 9.7e-6 without, polymer 2.1e-5 against 5.2e-6; the phase-pressure
    # form gave 1.7e-4 and 9.2e-5 (18x both)
    without = _roughness(schedule, {})
    with_pc = _roughness(schedule, {"capillary_pressure": 0.5})
    assert with_pc <= factor * without, (with_pc, without)

