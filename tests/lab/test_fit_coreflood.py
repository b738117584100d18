"""Single-phase polymer coreflood fit (Eqs. 2.6-2.8 through spflow.simulate): schedule, recovery, coverage, errors."""

import math

import numpy as np
import pytest

from oracles import permeability_reduction
from spflow.core.stage import StageContext
from spflow.plugins.forward.parameters import default_params
from spflow.plugins.lab import polymer_coreflood as pc
from spflow.plugins.lab.fit_result import FIT, FitError, fit_interval
from spflow.plugins.lab.polymer_fit_figures import polymer_coreflood_figure
from spflow.plugins.lab.polymer_fit_stages import FitPolymerCoreflood, FitPolymerRheology

TRUTH = {n: default_params()[n] for n in pc.NAMES}
CTX = StageContext("lab", verbose=False)


def test_schedule_rebuilt_from_injected_composition():
    ds = pc.synthetic_coreflood(TRUTH, None)
    slugs = pc.schedule_from_table(ds)
    assert [(s["pv"], s["polymer_ppm"]) for s in slugs] == [pytest.approx(x) for x in pc.DESIGN_SLUGS]
    assert all(s["salinity_ppm"] == pc.DESIGN_SALINITY_PPM for s in slugs)


def test_post_flush_pressure_is_darcy_times_residual_resistance_factor():
    # independent check of the fitted model: after the post-flush dp = dp_water * R_k(max C), Eqs. 2.7-2.8, with
    # dp_water = q mu L / (k A) in SI and R_k from the test oracle (C_SEP^SSLOPE with the Table 2.1 brine scaled).
    d = default_params()
    ds = pc.synthetic_coreflood(TRUTH, None)
    q, area = d["QINJ"] * 1e-6 / 60.0, math.pi * d["DIAMETER"] ** 2 / 4.0
    dp_water = q * d["VIS1"] * 1e-3 * d["LENGTH"] / (d["PERM"] * 9.869233e-16 * area)
    csep = d["C50"] * pc.DESIGN_SALINITY_PPM / 9400.0  # BETAP = 1: C_SEP = anions
    r_k = permeability_reduction(max(c for _, c in pc.DESIGN_SLUGS) * 1e-4, d["BRK"], d["CRK"], d["AP1"],
                                 d["PERM"] * 1e-3, d["PORO"], salinity_factor=csep ** d["SSLOPE"], cap=d["RKCAP"])
    assert ds["dp"].values[0] == pytest.approx(dp_water, rel=1e-6)
    assert ds["dp"].values[-1] / dp_water == pytest.approx(r_k, rel=2e-3)


def test_noise_free_history_recovers_the_truth():
    fit = pc.fit_coreflood(pc.synthetic_coreflood(TRUTH, None))
    for name, value in TRUTH.items():
        assert float(fit["estimate"].sel(param=name)) == pytest.approx(value, rel=1e-6), name
    FIT.validate(fit, stage="fit_polymer_coreflood", port="output")


def test_truth_inside_95_percent_interval_over_seeds():
    # a coarser grid than the stage default keeps the 20 fits cheap; data and fit share it (same model)
    hits = dict.fromkeys(pc.NAMES, 0)
    for seed in range(20):
        data = pc.synthetic_coreflood(TRUTH, np.random.default_rng(2000 + seed), cells=16)
        fit = pc.fit_coreflood(data, cells=16)
        lo, hi = fit_interval(fit, 0.95)
        for name in pc.NAMES:
            hits[name] += bool(lo.sel(param=name) <= TRUTH[name] <= hi.sel(param=name))
    assert all(h >= 16 for h in hits.values()), hits


def test_stage_with_rheology_input_and_figure(tmp_path):
    rheology = FitPolymerRheology().run(CTX)
    fit = FitPolymerCoreflood().run(CTX, rheology=rheology)
    assert fit.attrs["fixed_AP3"] == pytest.approx(float(rheology["estimate"].sel(param="AP3")))
    for name in pc.NAMES:
        est, std = float(fit["estimate"].sel(param=name)), float(fit["std"].sel(param=name))
        assert abs(est - TRUTH[name]) <= 4.0 * std, (name, est, std)
    assert polymer_coreflood_figure(fit, tmp_path / "fig2_4.png").stat().st_size > 10_000


def test_bad_histories_raise():
    ds = pc.synthetic_coreflood(TRUTH, None)
    off = ds.copy()
    off["pv"] = off["pv"] + 0.01
    with pytest.raises(FitError, match="grid"):
        pc.fit_coreflood(off)
    water = ds.copy()
    water["c_polymer_in"] = water["c_polymer_in"] * 0
    with pytest.raises(FitError, match="no polymer injected"):
        pc.fit_coreflood(water)
    neg = ds.copy()
    neg["dp"] = -neg["dp"]
    with pytest.raises(FitError, match="'dp' must be > 0"):
        pc.fit_coreflood(neg)
