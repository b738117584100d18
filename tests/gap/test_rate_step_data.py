"""A coreflood with injection-rate steps enters the diagnosis with its Δp at every step the ending slug's, never a
blend across the step, and the diagnosis names the steps it treats so (a note).

Reference: the simulation the noise-free coreflood was measured from, read at its own records (a record at a slug
end holds the ending slug's Δp: tests/forward/test_rate_steps.py) and, inside each slug run, the same simulation."""

import numpy as np

from spflow.plugins.forward.simulate import simulate
from spflow.plugins.gap.observed import load_experiments, rate_step_note
from spflow.synthetic import NoiseModel, make_coreflood

SCHEDULE = [{"pv": 0.4, "salinity_ppm": 9400.0, "rate_ml_min": 0.25},
            {"pv": 0.3, "salinity_ppm": 9400.0, "rate_ml_min": 1.0},
            {"pv": 0.3, "salinity_ppm": 9400.0, "rate_ml_min": 0.5}]


def test_dp_at_rate_steps_is_the_ending_slugs_and_the_steps_are_noted():
    data = make_coreflood(SCHEDULE, noise=NoiseModel.exact(pressure_interval_pv=0.01, tube_pv=0.01), seed=0,
                          cells=20, pv_step=0.01, experiment="R")
    (exp,) = load_experiments([data], 0.1)
    fine = simulate(SCHEDULE, cells=20, pv_step=0.01)
    at = [int(np.argmin(np.abs(fine["pv"].values - x))) for x in exp.pv]
    np.testing.assert_allclose(exp.observed["dp"], fine["dp"].values[at], rtol=1e-9)
    k = int(np.argmin(np.abs(exp.pv - 0.4)))
    assert exp.observed["dp"][k] < 0.5 * exp.observed["dp"][k + 1]  # 0.4 PV: still 0.25 ml/min, 0.5: 1 ml/min
    note = rate_step_note([exp])
    assert note is not None and "R at 0.4, 0.7 PV" in note
    assert rate_step_note(load_experiments(["BCF1"], 0.1)) is None
