"""Screening QoIs from a forward responses Dataset: final recovery and max pressure drop per experiment equal those
of direct ``simulate`` runs (experiments of different length, NaN padding), and per-time-step columns stop at each
experiment's end."""

import numpy as np
import pytest
import xarray as xr

from spflow.core.errors import SchemaError
from spflow.core.stage import StageContext
from spflow.plugins.forward.simulate import output_grid, simulate
from spflow.plugins.forward.stage import Forward
from spflow.plugins.screening.qois import qoi_coords, qoi_matrix, scalar_qois

ROWS = [{"AD31": 0.2, "E2C": 1.6}, {"AD31": 0.9, "E2C": 2.8}]
EXPERIMENTS = ["BCF1", "BCF2"]  # 4.23 and 4.79 PV: BCF1 is NaN-padded


@pytest.fixture(scope="module")
def responses():
    design = xr.Dataset({"values": (("sample", "param"), [[r["AD31"], r["E2C"]] for r in ROWS])},
                        coords={"param": ["AD31", "E2C"]})
    return Forward(experiments=EXPERIMENTS, cells=20).run(StageContext("fwd", verbose=False), design=design)


def test_final_recovery_and_max_dp_match_direct_runs(responses):
    q = scalar_qois(responses)
    assert q["recovery_final"].dims == ("sample", "experiment")
    assert q["recovery_final"].attrs["units"] == "1" and q["dp_max"].attrs["units"] == "Pa"
    for i, row in enumerate(ROWS):
        for exp in EXPERIMENTS:
            ref = simulate(exp, row, cells=20, pv_step=0.1)
            assert float(q["recovery_final"].sel(experiment=exp)[i]) == float(ref["recovery"][-1])
            assert float(q["dp_max"].sel(experiment=exp)[i]) == float(ref["dp"].max())


def test_time_series_columns_stop_at_each_experiment_end(responses):
    y, index = qoi_matrix(responses, ["recovery_final", "dp"])
    coords = qoi_coords(index)
    labels = coords["qoi"][1]
    assert labels[:2].tolist() == ["recovery_final:BCF1", "recovery_final:BCF2"]
    for exp in EXPERIMENTS:
        grid = output_grid(float(responses["total_pv"].sel(experiment=exp)), 0.1)
        cols = index.columns("dp", exp)
        np.testing.assert_allclose(index.pv[cols], grid)
        for i, row in enumerate(ROWS):
            np.testing.assert_array_equal(y[i, cols], simulate(exp, row, cells=20, pv_step=0.1)["dp"].values)
    assert np.isfinite(y).all()
    assert coords["qoi_units"][1][index.columns("dp")].tolist() == ["Pa"] * index.columns("dp").size


def test_nan_inside_an_experiment_is_an_error_not_skipped(responses):
    broken = responses.copy(deep=True)
    broken["dp"][1, 0, 5] = np.nan  # one sample only: a broken run, not the common grid's padding
    with pytest.raises(SchemaError, match="NaN for some samples only.*sample 1, experiment 'BCF1'"):
        scalar_qois(broken)
