"""The ``observations`` stage puts measured corefloods on the simulator's grid with each variable's own sampling
convention; references are computed here by hand from hand-built data and from a noise-free synthetic twin."""

import numpy as np
import pytest

from spflow.core.errors import ParameterError
from spflow.core.stage import StageContext
from spflow.io.format import build_coreflood, schedule_json
from spflow.plugins import observations
from spflow.plugins.observations import Observations, on_simulator_grid
from spflow.plugins.forward.simulate import simulate
from spflow.synthetic import NoiseModel, make_coreflood

SCHEDULE = [{"pv": 0.6, "salinity_ppm": 9400.0}]


def _handmade(tmp_path):
    """dp = 1000 + 500 pv sampled every 0.02 PV; tubes of 0.05 PV with oil cut 0.1 k; recovery = pv_tube_end / 2."""
    pv = np.arange(0, 0.6 + 1e-9, 0.02)
    start = np.arange(0, 0.6 - 1e-9, 0.05)
    end = start + 0.05
    oil_cut = 0.1 * np.arange(start.size) / start.size
    ds = build_coreflood(experiment="H1", source="test", pv=pv, dp=1000 + 500 * pv, tube_start=start, tube_end=end,
                         tubes={"oil_cut": oil_cut, "recovery": end / 2},
                         attrs={"schedule": schedule_json(SCHEDULE)})
    path = tmp_path / "h1.nc"
    ds.to_netcdf(path)
    return path, oil_cut


def test_each_variable_keeps_its_sampling_convention(tmp_path):
    path, oil_cut = _handmade(tmp_path)
    out = Observations(experiments=[str(path)], pv_step=0.1).run(StageContext("obs"))
    grid = out["pv"].values
    np.testing.assert_allclose(grid, np.arange(7) * 0.1, atol=1e-12)
    h = out.sel(experiment="H1")
    np.testing.assert_allclose(h["dp"].values, 1000 + 500 * grid, rtol=1e-12)  # point values
    np.testing.assert_allclose(h["recovery"].values[1:], grid[1:] / 2, rtol=1e-12)  # cumulative at tube ends
    assert np.isnan(h["recovery"].values[0])  # nothing collected before the first tube ends
    pairs = 0.5 * (oil_cut[0::2] + oil_cut[1::2])  # two 0.05-PV tubes per 0.1-PV interval
    np.testing.assert_allclose(h["oil_cut"].values[1:], pairs, rtol=1e-12)
    assert np.isnan(h["oil_cut"].values[0])
    assert out["oil_cut"].attrs["units"] == "1" and out["dp"].attrs["units"] == "Pa"
    assert float(out["total_pv"].sel(experiment="H1")) == pytest.approx(0.6)


RATE_STEPS = [{"pv": 0.4, "salinity_ppm": 9400.0, "rate_ml_min": 0.25},
              {"pv": 0.4, "salinity_ppm": 9400.0, "rate_ml_min": 0.5}]


def _stepped(pv):
    """dp = 1000 + 500 pv at 0.25 ml/min up to 0.4 PV (the end of the first slug included), twice that after."""
    return np.where(pv <= 0.4 + 1e-12, 1.0, 2.0) * (1000 + 500 * pv)


def test_dp_is_not_interpolated_across_a_rate_step(tmp_path, capsys):
    """Readings time-stamped at 0.395 and 0.405 PV straddle the step at 0.4; the grid point there is the end of
    the first slug (the left limit, extrapolated from 0.375-0.395), the next one the second slug's line; a reading
    0.02 PV short of a step is too far to extrapolate (NaN)."""
    pv = np.concatenate([np.arange(0, 0.4, 0.02) + 0.015, np.arange(0.405, 0.8, 0.02)])
    pv = pv[pv < 0.8]
    ds = build_coreflood(experiment="R1", source="test", pv=pv, dp=_stepped(pv), attrs={"schedule": schedule_json(
        RATE_STEPS)})
    grid = np.arange(9) * 0.1
    got = on_simulator_grid(ds, ["dp"], grid, 0.1, [0.4])["dp"]
    np.testing.assert_allclose(got[1:4], 1000 + 500 * grid[1:4], rtol=1e-12)
    assert got[4] == pytest.approx(1000 + 500 * 0.4, rel=1e-12)  # the left limit, 0.005 PV past the last reading
    np.testing.assert_allclose(got[5:8], 2 * (1000 + 500 * grid[5:8]), rtol=1e-12)
    blind = on_simulator_grid(ds, ["dp"], grid, 0.1)["dp"]  # interpolating across the step: a blend at 0.4
    assert abs(blind[4] / got[4] - 1.5) < 0.01
    far = pv[np.abs(pv - 0.395) > 1e-9]  # the last reading of the first slug at 0.375: 0.025 PV short
    ds_far = build_coreflood(experiment="R2", source="test", pv=far, dp=_stepped(far),
                             attrs={"schedule": schedule_json(RATE_STEPS)})
    assert np.isnan(on_simulator_grid(ds_far, ["dp"], grid, 0.1, [0.4])["dp"][4])
    path = tmp_path / "r1.nc"
    ds.to_netcdf(path)
    out = Observations(experiments=[str(path)], pv_step=0.1, variables=["dp"]).run(StageContext("obs"))
    assert out["dp"].values[0, 4] == pytest.approx(1000 + 500 * 0.4, rel=1e-12)
    assert "rate steps at 0.4 PV" in capsys.readouterr().err
    assert '"R1": [0.4]' in out.attrs["dp_rate_steps_pv"]


def test_rate_steps_pv_of_a_schedule():
    from spflow.plugins.forward.schedule import as_schedule

    sched = as_schedule([{"pv": 0.3, "salinity_ppm": 9400.0}, {"pv": 0.2, "salinity_ppm": 9400.0},
                         {"pv": 0.2, "salinity_ppm": 9400.0, "rate_ml_min": 0.5},
                         {"pv": 0.2, "salinity_ppm": 9400.0, "rate_ml_min": 0.5},
                         {"pv": 0.1, "salinity_ppm": 9400.0, "rate_ml_min": 1.0}])
    np.testing.assert_allclose(sched.rate_steps_pv(), [0.5, 0.9])
    assert as_schedule("BCF1").rate_steps_pv().size == 0


def test_noise_free_twin_matches_the_simulation_it_was_made_from():
    """The twin measures a 0.005-PV simulation; on the 0.1-PV grid, dp and recovery are that simulation's point
    values and oil cut the mean of its twenty 0.005-PV interval averages."""
    fine = simulate("BCF1", cells=40, pv_step=0.005)
    data = make_coreflood("BCF1", noise=NoiseModel.exact(), seed=0, cells=40, pv_step=0.005)
    grid = np.arange(43) * 0.1
    got = on_simulator_grid(data, ["dp", "oil_cut", "recovery"], grid, 0.1)
    at = np.searchsorted(fine["pv"].values, grid - 1e-9)
    np.testing.assert_allclose(got["dp"][:-1], fine["dp"].values[at][:-1], rtol=1e-9)  # transducer ends at 4.22
    np.testing.assert_allclose(got["recovery"][1:], fine["recovery"].values[at][1:], rtol=1e-9)
    cut = fine["oil_cut"].values[1:841].reshape(-1, 20).mean(axis=1)
    np.testing.assert_allclose(got["oil_cut"][1:], cut, atol=1e-12)
    out = Observations(experiments=["BCF1"]).run(StageContext("obs"))  # the bundled file, loaded by name
    assert list(out["experiment"].values) == ["BCF1"] and np.isfinite(out["dp"].values[0, :-1]).all()


def test_dead_volume_is_taken_out_of_the_effluent_series(tmp_path):
    """A noise-free twin behind an outlet line of 0.05 PV: corrected, its recovery and oil cut are the simulation's at
    the core outlet (the line is a pure translation by 0.05 PV); kept as measured, recovery lags by 0.05 PV and dp,
    read at the inlet, is the same either way."""
    fine = simulate("BCF1", cells=40, pv_step=0.005)
    pore_ml = make_coreflood("BCF1", noise=NoiseModel.exact(), cells=40, pv_step=0.005).attrs["pore_volume_ml"]
    data = make_coreflood("BCF1", noise=NoiseModel.exact(dead_volume_ml=0.05 * pore_ml), cells=40, pv_step=0.005)
    data.to_netcdf(tmp_path / "bcf1.nc")
    corrected = Observations(experiments=[str(tmp_path / "bcf1.nc")]).run(StageContext("obs")).isel(experiment=0)
    kept = Observations(experiments=[str(tmp_path / "bcf1.nc")], dead_volume="keep").run(StageContext("obs"))
    kept = kept.isel(experiment=0)
    assert float(corrected["dead_volume_pv"]) == pytest.approx(0.05, rel=1e-12)
    assert float(kept["dead_volume_pv"]) == 0.0
    grid = corrected["pv"].values
    at = np.searchsorted(fine["pv"].values, grid - 1e-9)
    recovery = corrected["recovery"].values
    finite = np.isfinite(recovery)
    assert finite[1:-2].all()  # the last tube now ends at 4.15 PV: nothing at 4.2 and at the 4.23-PV end
    np.testing.assert_allclose(recovery[finite], fine["recovery"].values[at][finite], rtol=1e-9, atol=1e-12)
    cut = corrected["oil_cut"].values
    fine_cut = np.full(grid.size, np.nan)  # the simulation's mean over each (pv - 0.1, pv] up to 4.2 PV
    fine_cut[1:43] = fine["oil_cut"].values[1:841].reshape(-1, 20).mean(axis=1)
    ok = np.isfinite(cut)
    assert ok[1:-2].all()  # the line-flush tube (-0.05, 0] is dropped; it overlaps no interval after 0
    np.testing.assert_allclose(cut[ok], fine_cut[ok], atol=1e-12)
    lagged = np.interp(grid - 0.05, fine["pv"].values, fine["recovery"].values)
    np.testing.assert_allclose(kept["recovery"].values[1:-1], lagged[1:-1], rtol=1e-9, atol=1e-12)
    np.testing.assert_array_equal(kept["dp"].values, corrected["dp"].values)


def test_bad_experiment_is_named_before_work(tmp_path):
    with pytest.raises(ParameterError, match="nope.nc"):
        Observations(experiments=[str(tmp_path / "nope.nc")]).run(StageContext("obs"))


@pytest.mark.parametrize("block_elements", [None, 1, 3 * 40])
def test_tube_averages_over_uneven_tubes_weigh_each_tube_by_its_overlap(monkeypatch, block_elements):
    """Tubes of uneven widths (one without an assay) averaged over the windows ``(pv - 0.1, pv]`` of the grid: the
    reference integrates the piecewise-constant tube values over each window in plain Python. Also with the
    windows x tubes overlap computed a window at a time and three windows at a time (the bound that keeps its
    memory small on fine grids)."""
    if block_elements is not None:
        monkeypatch.setattr(observations, "_OVERLAP_ELEMENTS", block_elements)
    rng = np.random.default_rng(7)
    widths = rng.uniform(0.01, 0.17, 40)
    end = 0.02 + np.cumsum(widths)
    start = end - widths
    cut = rng.uniform(0.0, 1.0, widths.size)
    cut[23] = np.nan  # a tube without an assay spoils the windows that touch it
    ds = build_coreflood(experiment="U1", source="test", pv=np.array([0.0, float(end[-1])]), dp=np.zeros(2),
                         tube_start=start, tube_end=end, tubes={"oil_cut": cut})
    grid = np.arange(0, float(end[-1]) + 0.35, 0.1)
    got = on_simulator_grid(ds, ["oil_cut"], grid, 0.1)["oil_cut"]
    for k, pv in enumerate(grid):
        lo = max(pv - 0.1, 0.0)
        if pv <= 0.0 or lo < start[0] or pv > end[-1]:
            assert np.isnan(got[k]), k  # not covered by the tubes
            continue
        parts = [(min(b, pv) - max(a, lo), c) for a, b, c in zip(start, end, cut) if min(b, pv) > max(a, lo)]
        if any(np.isnan(c) for _, c in parts):
            assert np.isnan(got[k]), k
            continue
        assert got[k] == pytest.approx(sum(w * c for w, c in parts) / sum(w for w, _ in parts), rel=1e-12), k
    assert np.isfinite(got).sum() >= 20 and np.isnan(got).sum() >= 4  # both kinds of window occur
