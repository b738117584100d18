"""The numerical-error part of the error model (inflated AR(1) scales), the base model's numerics reaching every
forward run, and degenerate error scales: left out of reports when the variable is not in the likelihood, an
error naming variable, experiment and file when it is."""

import dataclasses

import numpy as np
import pytest

from spflow.io.format import schedule_json
from spflow.plugins.forward.schedule import as_schedule
from spflow.plugins.forward.simulate import simulate
from spflow.plugins.gap.base_model import BaseModel
from spflow.plugins.gap.error_model import BlockErrorModel
from spflow.plugins.gap.layout import Block, Layout, make_layout
from spflow.plugins.gap.numerical_error import inflate
from spflow.plugins.gap.observed import load_experiments
from spflow.plugins.gap.prediction import Predictor
from spflow.synthetic import NoiseModel, measure

POLYMER_FLOOD = as_schedule([{"name": "WF", "pv": 0.5, "salinity_ppm": 9400.0},
                             {"name": "P", "pv": 0.6, "salinity_ppm": 9400.0, "polymer_ppm": 1000.0},
                             {"name": "CW", "pv": 0.6, "salinity_ppm": 9400.0}])


def test_inflated_scales_add_the_numerical_variance():
    a = np.array([1.0, 2.0, 3.0, 4.0])
    d = np.array([0.0, 1.5, 4.0, 0.5])
    blocks = (Block("dp", "X", np.arange(4), np.arange(4.0), np.zeros(4), np.zeros(4, int), BlockErrorModel(a, 0.7)),
              Block("recovery", "X", np.arange(4), np.arange(4.0), np.zeros(4), np.zeros(4, int),
                    BlockErrorModel(a, 1.0)),
              Block("oil_cut", "X", np.arange(4), np.arange(4.0), np.zeros(4), np.zeros(4, int),
                    BlockErrorModel(a, 0.0)))
    out = inflate(Layout(blocks), {("dp", "X"): d, ("recovery", "X"): d}, factor=2.0)
    np.testing.assert_allclose(out.blocks[0].noise.scale, [1.0, np.sqrt(4 + 9), np.sqrt(9 + 64), np.sqrt(16 + 1)])
    assert out.blocks[0].noise.phi == 0.7
    # integrated (random-walk) block: the increments of the numerical error are its innovations
    np.testing.assert_allclose(out.blocks[1].noise.scale, [1.0, np.sqrt(4 + 9), np.sqrt(9 + 25), np.sqrt(16 + 49)])
    np.testing.assert_array_equal(out.blocks[2].noise.scale, a)   # no spread given: unchanged


def test_the_base_models_scheme_and_output_step_reach_the_forward_runs(tmp_path):
    ds = measure(simulate(POLYMER_FLOOD, cells=12, pv_step=0.005), NoiseModel(), 1, experiment="PF",
                 source="test", schedule=schedule_json(POLYMER_FLOOD))
    (exp,) = load_experiments([ds], 0.1)
    config = {"cells": 12, "parameters": {"AP1": [5.0, 40.0]}}
    base = BaseModel.from_mapping(config)
    assert (base.scheme, base.pv_step) == ("tvd", 0.01)
    upwind = BaseModel.from_mapping(dict(config, scheme="upwind", pv_step=0.005))
    assert (upwind.scheme, upwind.pv_step) == ("upwind", 0.005)
    u = base.default_unit()
    tvd_dp = Predictor(base, [exp]).predict([(u, None)], ["PF"], ["dp"])[0]["PF"]["dp"]
    up_dp = Predictor(upwind, [exp]).predict([(u, None)], ["PF"], ["dp"])[0]["PF"]["dp"]
    coarse = dataclasses.replace(upwind, pv_step=0.01)
    up_coarse = Predictor(coarse, [exp]).predict([(u, None)], ["PF"], ["dp"])[0]["PF"]["dp"]
    # independent check of the scheme: the upwind prediction's last Δp is the direct upwind run's plus the
    # transducer's documented zero offset and drift over the injected PV (the deterministic measurement chain)
    direct = simulate(POLYMER_FLOOD, {**exp.core, "AP1": base.values(u)[0]}, cells=12, scheme="upwind",
                      pv_step=0.005)
    noise = NoiseModel()
    expected = float(direct["dp"].values[-1]) + noise.pressure_offset_pa + noise.pressure_drift_pa_per_pv * 1.7
    assert up_dp[-1] == pytest.approx(expected, rel=1e-6)
    assert not np.allclose(tvd_dp, up_dp)
    assert np.all(np.isfinite(up_coarse))


def test_degenerate_scales_name_variable_experiment_and_file(tmp_path):
    path = tmp_path / "polymer_only.nc"
    measure(simulate(POLYMER_FLOOD, cells=12, pv_step=0.005), NoiseModel(), 2, experiment="PF", source="test",
            schedule=schedule_json(POLYMER_FLOOD)).to_netcdf(path)
    exps = load_experiments([str(path)], 0.1)
    series = exps[0].observed["c_surfactant_out"]
    assert np.all(series[np.isfinite(series)] == 0.0)   # never injected, never produced
    # an assay of a species never injected that reads zero carries no information: left out with a note naming
    # the variable, the experiment and the file, whether the likelihood asks for it or not (other variables kept)
    for variables, report_only in ((["dp", "c_surfactant_out"], ()), (None, ["c_surfactant_out"])):
        notes = []
        layout = make_layout(exps, variables, report_only=report_only, dropped=notes)
        assert "c_surfactant_out" not in layout.variables and "dp" in layout.variables
        assert len(notes) == 1 and "'c_surfactant_out'" in notes[0] and "'PF'" in notes[0]
        assert "polymer_only.nc" in notes[0] and "never injects" in notes[0]
