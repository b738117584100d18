"""Surrogate figures (thesis Figs. 3.3-3.5, 3.7-3.9, 3.15): each function writes a PNG, and the numbers it plots are
checked against independent recomputations -- brute-force R² on the pooled values, Monte Carlo moments of the PCE
itself, the surrogates' own predictions, a direct count of the ±2σ coverage -- on a smooth non-polynomial function of
two parameters (so the PCE is not exact), and on a small ``adaptive_pce`` run of the simulator (16 runs, 20 cells)."""

import numpy as np
import pytest
import xarray as xr

from spflow.core.errors import ParameterError
from spflow.core.stage import StageContext
from spflow.plugins.design.parameter_space import ParameterSpace
from spflow.plugins.design.thesis_tables import TABLE_3_2
from spflow.plugins.forward.stage import RESPONSE_UNITS, RESPONSES
from spflow.plugins.surrogates.adaptive_design import AdaptivePCE
from spflow.plugins.surrogates.contract import load_surrogate
from spflow.plugins.surrogates.figure_data import POOLED, band_data, error_history, moment_data, scatter_data
from spflow.plugins.surrogates.figures import (band_figure, convergence_figure, moments_figure,
                                               proxy_vs_simulator_figure)
from spflow.plugins.surrogates.kriging_stage import GPStage
from spflow.plugins.surrogates.pce_stage import PCEStage
from spflow.plugins.surrogates.validation import SurrogateValidation

CTX = StageContext(node="test", verbose=False)
NAMES = ["AD31", "HBNC71"]
LOWER, UPPER = np.array([0.0, 0.01]), np.array([2.0, 0.02])
PV = np.linspace(0.0, 2.0, 9)


def _space():
    return xr.Dataset({"lower": ("param", LOWER, {"units": "per-parameter"}),
                       "upper": ("param", UPPER, {"units": "per-parameter"}),
                       "default": ("param", (LOWER + UPPER) / 2, {"units": "per-parameter"}),
                       "unit": ("param", ["1", "1"])}, coords={"param": NAMES})


def _design(x):
    return xr.Dataset({"values": (("sample", "param"), x, {"units": "per-parameter"})},
                      coords={"sample": np.arange(len(x)), "param": NAMES})


def _model(x):
    """A smooth, non-polynomial response (sample, pv) per variable: dp in Pa (peaks inside the PV range, where its
    sensitivity to the inputs changes), recovery as a fraction."""
    z = 2 * (x - LOWER) / (UPPER - LOWER) - 1
    a, b = z[:, :1], z[:, 1:]
    shape = 1 + 0.5 * a + 0.3 * b**2 + 0.2 * np.sin(2 * a * b)
    return {"dp": 1e5 * (shape + 3 * (1 + 0.5 * b) * PV * np.exp(-PV)),
            "recovery": 0.4 * shape * (1 - np.exp(-PV * (1 + 0.5 * a)))}


def _responses(x):
    truth = _model(x)
    data = {name: truth.get(name, np.zeros((len(x), PV.size)))[:, None, :] for name in RESPONSE_UNITS}
    ds = xr.Dataset({name: (("sample", "experiment", "pv"), v, {"units": RESPONSE_UNITS[name]})
                     for name, v in data.items()} | {"total_pv": ("experiment", [PV[-1]], {"units": "1"})},
                    coords={"sample": np.arange(len(x)), "experiment": ["BCF1"], "pv": PV})
    RESPONSES.validate(ds, stage="test", port="responses")
    return ds


def _points(n, seed):
    return np.random.default_rng(seed).uniform(LOWER, UPPER, (n, 2))


@pytest.fixture(scope="module")
def fits():
    x, xv = _points(40, 0), _points(60, 1)
    train = {"space": _space(), "design": _design(x), "responses": _responses(x)}
    pce = PCEStage(degree_max=4).run(CTX, **train)
    gp = GPStage(share="variable", restarts=1).run(CTX, **train)
    return {"pce": pce, "gp": gp, "design": _design(xv), "responses": _responses(xv), "x": xv}


def _is_png(path):
    data = path.read_bytes()
    return data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) > 10_000


def test_scatter_numbers_and_figure(fits, tmp_path):
    d = scatter_data(fits["pce"], fits["design"], fits["responses"])
    truth = _model(fits["x"])
    predicted = load_surrogate(fits["pce"]).predict(fits["x"])[0]
    v = SurrogateValidation().run(CTX, surrogate=fits["pce"], design=fits["design"], responses=fits["responses"])
    for k, name in enumerate(("dp", "recovery")):
        np.testing.assert_allclose(d[f"{name}_simulator"].values, truth[name], rtol=1e-14)
        np.testing.assert_allclose(d[f"{name}_proxy"].values, predicted[:, k * PV.size:(k + 1) * PV.size])
        y, mu = truth[name].ravel(), d[f"{name}_proxy"].values.ravel()
        r2 = 1 - np.sum((y - mu) ** 2) / np.sum((y - y.mean()) ** 2)
        assert float(d["r2_pooled"].sel(variable=name)) == pytest.approx(r2, rel=1e-12)
        assert float(d["l2_pooled"].sel(variable=name)) == pytest.approx(np.linalg.norm(y - mu) / np.linalg.norm(y))
        for key in ("r2_max", "r2_final"):
            assert float(d[key].sel(variable=name)) == pytest.approx(float(v[key][k]), rel=1e-12)
    assert 0.99 < float(d["r2_max"].sel(variable="dp")) < 1.0  # a good but not exact fit
    assert d["dp_proxy"].attrs["units"] == "Pa"
    path = proxy_vs_simulator_figure({"PCE": fits["pce"], "GP": fits["gp"]}, fits["design"], fits["responses"],
                                     tmp_path / "scatter.png")
    assert _is_png(path)


def test_pce_moments_equal_monte_carlo_moments_of_the_pce(fits, tmp_path):
    d = moment_data(fits["pce"], fits["responses"])
    assert d.attrs["moments"].startswith("analytic")
    model = load_surrogate(fits["pce"])
    n = 200_000
    mc = model.predict(np.random.default_rng(7).uniform(LOWER, UPPER, (n, 2)))[0]
    for k, name in enumerate(("dp", "recovery")):
        block = mc[:, k * PV.size:(k + 1) * PV.size]
        sd = block.std(axis=0)
        # mean: standard error sd/sqrt(n); variance: standard error ~ sqrt((m4 - sd^4)/n)
        np.testing.assert_array_less(np.abs(d[f"{name}_proxy_mean"].values - block.mean(axis=0)),
                                     5 * sd / np.sqrt(n) + 1e-12 * np.abs(block).max())
        m4 = np.mean((block - block.mean(axis=0)) ** 4, axis=0)
        np.testing.assert_array_less(np.abs(d[f"{name}_proxy_std"].values ** 2 - sd ** 2),
                                     5 * np.sqrt(np.maximum(m4 - sd ** 4, 0) / n) + 1e-12 * np.abs(block).max() ** 2)
        truth = _model(fits["x"])[name]
        np.testing.assert_allclose(d[f"{name}_sample_mean"].values, truth.mean(axis=0), rtol=1e-12)
        np.testing.assert_allclose(d[f"{name}_sample_std"].values, truth.std(axis=0), rtol=1e-12, atol=1e-15)
    v = SurrogateValidation().run(CTX, surrogate=fits["pce"], design=fits["design"], responses=fits["responses"])
    np.testing.assert_allclose(d["mean_l2_error"].values, v["mean_l2_error"].values, rtol=1e-12)
    np.testing.assert_allclose(d["variance_l2_error"].values, v["variance_l2_error"].values, rtol=1e-12)
    assert _is_png(moments_figure({"PCE": fits["pce"], "GP": fits["gp"]}, fits["responses"], tmp_path / "m.png",
                                  design=fits["design"]))


def test_moments_of_a_kind_without_analytic_moments_come_from_its_predictions(fits):
    with pytest.raises(ParameterError, match="no analytic moments"):
        moment_data(fits["gp"], fits["responses"])
    d = moment_data(fits["gp"], fits["responses"], design=fits["design"])
    predicted = load_surrogate(fits["gp"]).predict(fits["x"])[0]
    np.testing.assert_allclose(d["dp_proxy_mean"].values, predicted[:, :PV.size].mean(axis=0), rtol=1e-12)
    np.testing.assert_allclose(d["recovery_proxy_std"].values, predicted[:, PV.size:].std(axis=0), rtol=1e-12)
    assert "predicted mean at the 60 validation points" in d.attrs["moments"]


def test_band_uses_the_surrogates_predictions_and_counts_coverage(fits, tmp_path):
    d = band_data(fits["gp"], fits["design"], fits["responses"], n_show=4, reference=fits["pce"])
    mean, var = load_surrogate(fits["gp"]).predict(fits["x"])
    ref = load_surrogate(fits["pce"]).predict(fits["x"][:4])[0]
    truth = _model(fits["x"])
    for k, name in enumerate(("dp", "recovery")):
        cols = slice(k * PV.size, (k + 1) * PV.size)
        np.testing.assert_allclose(d[f"{name}_mean"].values, mean[:4, cols], rtol=1e-12)
        np.testing.assert_allclose(d[f"{name}_std"].values, np.sqrt(var[:4, cols]), rtol=1e-12)
        np.testing.assert_allclose(d[f"{name}_reference_mean"].values, ref[:, cols], rtol=1e-12)
        np.testing.assert_allclose(d[f"{name}_simulator"].values, truth[name][:4], rtol=1e-14)
        count = sum(abs(mean[i, c] - truth[name][i, j]) <= 2 * np.sqrt(var[i, c]) + 1e-12 * np.abs(truth[name]).max()
                    for i in range(len(truth[name])) for j, c in enumerate(range(cols.start, cols.stop)))
        assert float(d["coverage"].sel(variable=name)) == pytest.approx(count / truth[name].size)
    assert 0.0 < float(d["coverage"].sel(variable="dp")) <= 1.0
    assert _is_png(band_figure(fits["gp"], fits["design"], fits["responses"], tmp_path / "band.png",
                               reference=fits["pce"]))


def test_bad_inputs_fail_before_any_work(fits, tmp_path):
    with pytest.raises(ParameterError, match="n_show must be an integer in \\[1, 60\\]"):
        band_figure(fits["gp"], fits["design"], fits["responses"], tmp_path / "b.png", n_show=0)
    with pytest.raises(ParameterError, match="no surrogate output for variable 'oil_cut'"):
        proxy_vs_simulator_figure(fits["pce"], fits["design"], fits["responses"], tmp_path / "s.png",
                                  variables=["oil_cut"])
    with pytest.raises(ParameterError, match="responses have 59 samples"):
        scatter_data(fits["pce"], fits["design"], fits["responses"].isel(sample=slice(0, 59)))
    with pytest.raises(ParameterError, match="without repeats"):
        moment_data(fits["pce"], fits["responses"], variables=["dp", "dp"])
    with pytest.raises(ParameterError, match="adaptive_pce"):
        error_history(fits["pce"])
    assert not list(tmp_path.iterdir())


@pytest.fixture(scope="module")
def grown():
    """PCE fits on nested designs of 40 and 20 points (given largest first)."""
    x = _points(40, 0)
    return [PCEStage(degree_max=3).run(CTX, space=_space(), design=_design(x[:n]), responses=_responses(x[:n]))
            for n in (40, 20)]


def test_error_history_of_growing_fits(grown):
    h = error_history(grown)
    np.testing.assert_array_equal(h["n_s"].values, [20, 40])
    for k, fit in enumerate(grown[::-1]):
        model = load_surrogate(fit)
        for name in ("dp", "recovery"):
            cols = model.outputs.variable == name
            assert float(h["loo"].isel(n_s=k).sel(variable=name)) == pytest.approx(model.loo[cols].mean())
            assert float(h["empirical"].isel(n_s=k).sel(variable=name)) == pytest.approx(model.empirical[cols].mean())
        assert h["degree"].values[k] == fit.attrs["degree"]


def test_convergence_figure_from_an_adaptive_pce_run(grown, tmp_path):
    names = ["AD31", "HBNC71"]
    space = ParameterSpace(names=names, ranges={n: TABLE_3_2[n] for n in names}).run(CTX)
    adaptive = AdaptivePCE(n_initial=8, n_increment=8, n_max=16, tolerance=0.0, degree_max=2, cells=20,
                           solver="lars").run(CTX, space=space)
    h = error_history(adaptive)
    assert list(h["variable"].values) == [POOLED]
    np.testing.assert_array_equal(h["n_s"].values, [8, 16])
    model = load_surrogate(adaptive)
    assert float(h["loo"].values[-1, 0]) == pytest.approx(np.mean(model.loo))  # the last entry is the final fit
    assert float(h["empirical"].values[-1, 0]) == pytest.approx(np.mean(model.empirical))
    assert _is_png(convergence_figure(adaptive, tmp_path / "adaptive.png"))
    assert _is_png(convergence_figure({"adaptive": adaptive, "OLS fits": grown}, tmp_path / "both.png"))
