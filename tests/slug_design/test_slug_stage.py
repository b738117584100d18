"""The ``slug_design`` stage on tiny budgets: every evaluation recomputed independently from the simulator."""

import numpy as np
import pytest
import xarray as xr

import spflow
from spflow.core.errors import ParameterError
from spflow.core.stage import StageContext
from spflow.plugins.forward.schedule import Schedule, Slug
from spflow.plugins.slug_design.stage import SlugDesign

TINY = {"cells": 20, "n_init": 4, "max_iter": 2, "min_iter": 0, "pv_step": 0.02, "n_fronts": 10, "knee_draws": 3,
        "seed": 5}
LB_PER_BBL = 1000.0 * 0.158987294928 / 0.45359237  # 1 bbl of water [lb], exact unit definitions


def schedule_by_hand(s_htds, s_sp, s_p, total=4.5):
    return Schedule((Slug("IWF", 1.0, 9400.0), Slug("HTDS", s_htds, 17500.0),
                     Slug("SP", s_sp, 17500.0, 6780.0 * 0.25 / s_sp, 2500.0 * 0.25 / s_sp),
                     Slug("P", s_p, 9400.0, 0.0, 2500.0 * 0.25 / s_p), Slug("EWF", total - 1 - s_htds - s_sp - s_p,
                                                                            9400.0)))


def npv_by_hand(x, response, mu_per_year):
    """Eqs. 4.7-4.11 term by term for the stage's default scale-up (1e5 bbl, 3.5/13 PV/year from 1 PV)."""
    rate, vp = 3.5 / 13, 1.0e5
    pv, cut = response["pv"].values, response["oil_cut"].values
    s_htds, s_sp, s_p = x
    # chemical slugs as (start PV, end PV, $ per PV)
    slugs = [(1.0, 1.0 + s_htds, 17500e-6 * 0.5),
             (1.0 + s_htds, 1.0 + s_htds + s_sp,
              17500e-6 * 0.5 + 6780e-6 * 0.25 / s_sp * 5.0 + 2500e-6 * 0.25 / s_sp * 2.0),
             (1.0 + s_htds + s_sp, 1.0 + s_htds + s_sp + s_p, 9400e-6 * 0.5 + 2500e-6 * 0.25 / s_p * 2.0)]
    total = -2.0e5
    for j in range(1, 14):
        a, b = 1.0 + rate * (j - 1), 1.0 + rate * j
        oil = 0.0
        for k in range(1, pv.size):  # interval (pv[k-1], pv[k]] at the average oil cut cut[k]
            oil += cut[k] * max(0.0, min(b, pv[k]) - max(a, pv[k - 1]))
        chem = sum(usd * max(0.0, min(b, hi) - max(a, lo)) for lo, hi, usd in slugs) * vp * LB_PER_BBL
        price = 75.0 * np.exp(mu_per_year * j)
        total += (price * oil * vp - chem - 1.0e4) / 1.2 ** j
    return total


def run_stage(posterior=None, **params):
    return SlugDesign(**(TINY | params)).run(StageContext("slug_design", n_jobs=1, verbose=False),
                                              posterior=posterior)


def test_every_evaluation_matches_an_independent_npv_and_pressure_drop():
    out = run_stage(drift=-1e-5, volatility=0.0)  # no posterior, no volatility: deterministic objectives
    assert out.sizes["evaluation"] == TINY["n_init"] + TINY["max_iter"]
    assert out["chosen_at"].values.tolist() == [0, 0, 0, 0, 1, 2]
    for x, (neg_npv, max_dp) in zip(out["design"].values, out["observed"].values):
        assert np.all((x >= 0.1) & (x <= 1.0))
        response = spflow.simulate(schedule_by_hand(*x), cells=20, pv_step=0.02)
        assert max_dp == pytest.approx(float(response["dp"].max()) / 1e3, rel=1e-12)
        assert -neg_npv * 1e6 == pytest.approx(npv_by_hand(x, response, -1e-5 * 365), rel=1e-9, abs=1e-3)
    assert out.attrs["total_pv"] == pytest.approx(4.5)
    assert out["observed"].attrs["units_variable"] == "objective_units" and "units" not in out["observed"].attrs
    assert out["objective_units"].values.tolist() == ["1e6", "kPa"]  # million US dollars (M$), kPa
    # the knee is one of the projected-front designs; without a posterior it is simulated once
    assert bool(out["on_front"].values[int(out["knee_index"])])
    np.testing.assert_array_equal(out["knee_design"].values, out["design"].values[int(out["knee_index"])])
    assert out.sizes["knee_draw"] == 1 and out["knee_dp"].attrs["units"] == "kPa"
    # the hypervolume reference: default NPV 0 M$ and 50 kPa, in the minimised objectives (-NPV, max dp)
    assert out["reference"].values.tolist() == [0.0, 50.0]


def posterior_of(values: np.ndarray, names: list[str]) -> xr.Dataset:
    """A minimal posterior Dataset (chain, draw, param) with the fields the stage reads."""
    chains, draws, _ = values.shape
    return xr.Dataset(
        {"theta": (("chain", "draw", "param"), values),
         "sigma": (("chain", "draw", "block"), np.ones((chains, draws, 1))),
         "log_likelihood": (("chain", "draw"), np.zeros((chains, draws)), {"units": "1"}),
         "log_posterior": (("chain", "draw"), np.zeros((chains, draws)), {"units": "1"}),
         "acceptance": ("chain", np.full(chains, 0.3), {"units": "1"}),
         "lower": ("param", values.min(axis=(0, 1))), "upper": ("param", values.max(axis=(0, 1))),
         "block_variable": ("block", np.array(["dp"])), "block_experiment": ("block", np.array(["BCF1"]))},
        coords={"chain": np.arange(chains), "draw": np.arange(draws), "param": names, "block": ["dp/BCF1"]},
        attrs={"sampler": "test", "noise": "test"})


def test_posterior_draws_drive_the_simulations():
    names = ["GAMHF", "E2C"]
    values = np.array([[[50.0, 1.5], [70.0, 2.5], [60.0, 2.0]], [[55.0, 1.8], [65.0, 2.2], [52.0, 2.4]]])
    out = run_stage(posterior=posterior_of(values, names), drift=1e-5)
    flat = values.reshape(-1, 2)
    draws = out["posterior_draw"].values
    assert np.all((draws >= 0) & (draws < 6)) and out.attrs["posterior_draws"] == 6
    for x, index, max_dp in zip(out["design"].values, draws, out["observed"].values[:, 1]):
        response = spflow.simulate(schedule_by_hand(*x), dict(zip(names, flat[index])), cells=20, pv_step=0.02)
        assert max_dp == pytest.approx(float(response["dp"].max()) / 1e3, rel=1e-12)
    assert out.sizes["knee_draw"] == TINY["knee_draws"]
    knee = out["knee_design"].values
    for k, index in enumerate(out["knee_posterior_draw"].values):
        response = spflow.simulate(schedule_by_hand(*knee), dict(zip(names, flat[index])), cells=20, pv_step=0.02)
        np.testing.assert_allclose(out["knee_dp"].values[k], response["dp"].values / 1e3, rtol=1e-12)


@pytest.mark.parametrize("params, field", [({"drift": 2.0}, "drift"), ({"n_init": 1}, "n_init"),
                                           ({"cells": 2}, "cells"), ({"injection_rate": 0.2}, "injection_rate")])
def test_bad_parameters_are_named_before_any_work(params, field):
    with pytest.raises(ParameterError, match=field):
        SlugDesign(**params).realisations(None)


@pytest.mark.parametrize("reference", [[1.0], [0.0, float("nan")], [0.0, "x"]])
def test_bad_reference_fails_when_the_stage_is_built(reference):
    with pytest.raises(ParameterError, match="parameter 'reference'"):
        SlugDesign(reference=reference)


def test_posterior_with_unknown_parameter_is_rejected_before_any_simulation():
    bad = posterior_of(np.ones((1, 2, 1)), ["NOT_A_PARAMETER"])
    with pytest.raises(ParameterError, match="NOT_A_PARAMETER"):
        SlugDesign(**TINY).realisations(bad)


def test_objective_draws_do_not_depend_on_the_workers_and_repeat_with_the_seed():
    from joblib import Parallel

    from spflow.plugins.slug_design.objectives import NoisyObjective, Realisations, SlugDesignProblem
    from spflow.plugins.slug_design.oil_price import OilPriceModel

    names = ["GAMHF", "E2C"]
    theta = np.array([[50.0, 1.5], [70.0, 2.5], [60.0, 2.0]])
    problem = SlugDesignProblem(price=OilPriceModel(alpha=1e-2), cells=20, pv_step=0.02)
    X = np.array([[0.3, 0.3, 0.3]] * 4)
    serial = NoisyObjective(Realisations(problem, theta, names), Parallel(n_jobs=1), seed=9)
    y1 = serial(X)
    y2 = NoisyObjective(Realisations(problem, theta, names), Parallel(n_jobs=2), seed=9)(X)
    np.testing.assert_array_equal(y1, y2)
    # one design, four realisations: max dp changes only with the posterior draw, NPV also with the price path
    draws = np.array([e["draw"] for e in serial.log])
    assert (np.bincount(draws) > 1).any()  # 4 draws of 3 rows: some row twice
    for d in np.unique(draws):
        same = draws == d
        assert np.ptp(y1[same, 1]) == 0.0
        if same.sum() > 1:
            assert np.ptp(y1[same, 0]) > 0.0
    assert len(np.unique(y1[:, 0])) == 4
    # the next call continues the random stream: new draws, not a repeat
    assert not np.array_equal(serial(X), y1)


def test_bgo_iterations_are_reported_as_progress():
    reports = []
    ctx = StageContext("slug", n_jobs=1, verbose=False, report=lambda *report: reports.append(report))
    SlugDesign(**(TINY | {"drift": -1e-5, "volatility": 0.0})).run(ctx)
    bgo = [r for r in reports if r[3] == "BGO iterations"]
    assert bgo[0] == ("slug", 0, TINY["max_iter"], "BGO iterations")  # after the initial design
    assert bgo[-1] == ("slug", TINY["max_iter"], TINY["max_iter"], "BGO iterations")
