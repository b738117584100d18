"""The forward stage simulates study experiments with their own core, rate and schedule: {name, schedule,
params} mappings, whose params override ``fixed`` and are overridden by the design's values."""

import numpy as np
import pytest
import xarray as xr

from spflow.core.errors import ParameterError
from spflow.core.stage import StageContext
from spflow.plugins.forward.simulate import simulate
from spflow.plugins.forward.stage import Forward

SLUGS = [{"name": "WF", "pv": 0.6, "salinity_ppm": 9400.0},
         {"name": "P", "pv": 0.4, "salinity_ppm": 9400.0, "polymer_ppm": 1500.0}]
CORE = {"LENGTH": 0.30, "DIAMETER": 0.0381, "PORO": 0.19, "PERM": 350.0, "SWI": 0.28, "QINJ": 0.5}


def _design(values):
    return xr.Dataset({"values": (("sample", "param"), np.array([[values]]))}, coords={"param": ["HBNC71"]})


def test_mapping_experiments_use_their_own_params_over_fixed_under_the_design():
    stage = Forward(experiments=[{"name": "core7", "schedule": {"name": "p", "slugs": SLUGS}, "params": CORE},
                                 "BCF1"],
                    fixed={"VIS2": 20.0, "PERM": 900.0}, cells=12, pv_step=0.1)
    out = stage.run(StageContext("forward"), design=_design(0.017))
    assert list(out["experiment"].values) == ["core7", "BCF1"]
    own = simulate(SLUGS, dict(CORE, VIS2=20.0, HBNC71=0.017), cells=12, pv_step=0.1)
    bundled = simulate("BCF1", {"VIS2": 20.0, "PERM": 900.0, "HBNC71": 0.017}, cells=12, pv_step=0.1)
    grid = np.round(out["pv"].values, 9)
    for name in ("dp", "recovery"):
        mine = out[name].sel(experiment="core7").values[0]
        at = np.searchsorted(grid, np.round(own["pv"].values, 9))
        np.testing.assert_array_equal(mine[at], own[name].values)
        theirs = out[name].sel(experiment="BCF1").values[0]
        np.testing.assert_array_equal(theirs[np.searchsorted(grid, np.round(bundled["pv"].values, 9))],
                                      bundled[name].values)
    assert float(out["total_pv"].sel(experiment="core7")) == pytest.approx(1.0)


@pytest.mark.parametrize("experiments, message", [
    (["BCF4"], "experiments[0] = 'BCF4': unknown bundled experiment"),
    ([{"name": "a", "schedule": SLUGS, "parms": {}}], "unknown key(s) ['parms']; allowed keys ['name', 'schedule'"),
    ([{"name": "a"}], "experiments[0] ('a'): missing 'schedule'"),
    ([{"name": "a", "schedule": SLUGS, "params": {"LENGTH": 50.0}}], "parameter LENGTH = 50.0 is out of range"),
    ([{"name": "a", "schedule": [{"pv": -1, "salinity_ppm": 1}]}], "experiments[0] ('a'): schedule: slug 0"),
    ([{"name": "a", "schedule": SLUGS}, {"name": "a", "schedule": SLUGS}], "names ['a'] occur more than once"),
    ([], "the list is empty"),
])
def test_bad_experiments_are_rejected_when_the_stage_is_built(experiments, message):
    with pytest.raises(ParameterError) as err:
        Forward(experiments=experiments)
    assert message in str(err.value)


def test_study_experiments_feed_the_forward_stage_and_the_gap_diagnosis(tmp_path):
    from spflow.plugins.gap.observed import load_experiments
    from spflow.study import load_study
    from study_project import write_project

    study = load_study(write_project(tmp_path))
    stage = Forward(experiments=study.forward_experiments(), fixed=study.fixed, cells=8, pv_step=0.5)
    out = stage.run(StageContext("forward"))
    assert list(out["experiment"].values) == ["core7"] and float(out["total_pv"][0]) == pytest.approx(3.0)
    (seen,) = load_experiments([study.experiment("core7").observations()], pv_step=0.1)
    assert seen.core == pytest.approx({"LENGTH": 0.30, "DIAMETER": 0.0381, "PORO": 0.19, "PERM": 350.0,
                                       "SWI": 0.28, "QINJ": 0.5})
    assert seen.measurement.dead_volume_ml == 0.5 and seen.noise_from_data
