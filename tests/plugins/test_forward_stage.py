"""The ``forward`` stage: design x experiments -> responses, equal to direct ``simulate`` calls, bit-identical in
serial and parallel, and validating every sample before simulating any."""

import numpy as np
import pytest
import xarray as xr

import spflow
import spflow.plugins.forward.stage as forward_stage
from spflow.plugins.forward.simulate import simulate


def _design(values, names=("AD31", "HBNC71")):
    return xr.Dataset(
        {"values": (("sample", "param"), np.asarray(values, dtype=float), {"units": "per-parameter"})},
        coords={"sample": np.arange(len(values)), "param": list(names)},
    )


def _pipeline(design, **params):
    p = spflow.Pipeline("fwd").add_data("design", design)
    p.add("sim", "forward", inputs={"design": "design"},
          params={"experiments": ["BCF1", "BCF3"], "cells": 30, "pv_step": 0.1, **params})
    return p


def test_responses_equal_direct_simulation_and_are_padded(tmp_path):
    design = _design([[0.2, 0.012], [0.5, 0.018]])
    out = spflow.run(_pipeline(design), cache=tmp_path)["sim"]
    assert out["dp"].dims == ("sample", "experiment", "pv")
    assert out["dp"].attrs["units"] == "Pa" and out["recovery"].attrs["units"] == "1"
    for i, (ad31, hbnc71) in enumerate([(0.2, 0.012), (0.5, 0.018)]):
        for exp in ["BCF1", "BCF3"]:  # BCF3 ends at 4.1 PV, a point BCF1 has as 41 * 0.1
            ref = simulate(exp, {"AD31": ad31, "HBNC71": hbnc71}, cells=30, pv_step=0.1)
            got = out.sel(sample=i, experiment=exp)
            ref_pv = np.round(ref["pv"].values, 9)
            own = np.isin(out["pv"].values, ref_pv)  # each point labelled by its own PV value
            assert own.sum() == ref.sizes["pv"]
            for name in ["dp", "oil_cut", "recovery", "c_polymer_out", "c_surfactant_out", "salinity_out"]:
                np.testing.assert_array_equal(got[name].sel(pv=ref_pv).values, ref[name].values)
            assert np.isnan(got["dp"].values[~own]).all()
            assert float(out["total_pv"].sel(experiment=exp)) == pytest.approx(float(ref["pv"][-1]))


def test_serial_and_parallel_are_bit_identical(tmp_path):
    design = _design([[0.1, 0.011], [0.3, 0.013], [0.6, 0.015], [0.9, 0.019]])
    serial = spflow.run(_pipeline(design), cache=tmp_path / "s", jobs=1)["sim"]
    parallel = spflow.run(_pipeline(design), cache=tmp_path / "p", jobs=2)["sim"]
    xr.testing.assert_identical(serial, parallel)


def test_every_sample_validated_before_any_simulation(tmp_path, monkeypatch):
    calls = []
    monkeypatch.setattr(forward_stage, "simulate", lambda *a, **k: calls.append(a))
    design = _design([[0.2, 0.012], [0.2, 0.9]])  # HBNC71 = 0.9 is outside its bounds
    with pytest.raises(spflow.StageError, match="HBNC71"):
        spflow.run(_pipeline(design), cache=tmp_path)
    assert calls == []
