"""The next-experiment designer: closed-form discrimination against Monte Carlo, a rate-step toy, table and files.

References are computed in the tests: Monte Carlo with scipy's multivariate normal log densities on a linear-
Gaussian pair (raw, unwhitened coordinates), the analytic power of two equal-covariance Gaussians, and, for the
ranking, the physics of the toy (shear thinning and a calibrated Newtonian viscosity law agree at the reference
rate and only a rate change separates them).
"""

from __future__ import annotations

import json
import math
import shutil
from dataclasses import replace

import numpy as np
import pytest
from scipy.linalg import cholesky, solve_triangular
from scipy.stats import multivariate_normal, norm

from spflow.core.errors import ParameterError
from spflow.io.schedule_file import read_schedule_file, schedule_toml
from spflow.plugins.forward.schedule import as_schedule
from spflow.plugins.gap.base_model import BaseModel
from spflow.plugins.gap.design_check import realised_accuracy
from spflow.plugins.gap.design_space import DESIGN_KINDS, design_space
from spflow.plugins.gap.layout import make_layout
from spflow.plugins.gap.least_squares import fit
from spflow.plugins.gap.numerical_error import DEFAULT_VARIANTS, NumericalTerm
from spflow.plugins.gap.next_experiment import (Hypothesis, decision_power, hypotheses_from_fits, log_ratio_moments,
                                                rank_designs)
from spflow.plugins.gap.observed import load_experiments
from spflow.plugins.gap.prediction import Predictor
from spflow.plugins.gap.proposal import proposal_summary, write_proposal
from spflow.study import bundled_study_path, load_study
from spflow.study.proposed_experiment import study_experiment_toml
from spflow.synthetic import NoiseModel, make_coreflood


# -- closed form against Monte Carlo ----------------------------------------------------------------------------


def _linear_gaussian_pair():
    """Two calibrated linear models y = X_m theta_m + e with AR(1) noise R and parameter covariances C_m: their
    predictive distributions N(X_m theta_m, R + X_m C_m X_m') in raw coordinates."""
    rng = np.random.default_rng(5)
    n = 12
    t = np.linspace(0.0, 1.0, n)
    sd = 0.1 + 0.2 * t
    phi = 0.6
    corr = phi ** np.abs(np.subtract.outer(np.arange(n), np.arange(n)))
    noise = corr * np.outer(sd, sd)
    xa = np.column_stack([np.ones(n), t])
    xb = np.column_stack([np.ones(n), t**2, np.sin(3 * t)])
    mean_a = xa @ np.array([1.0, 0.5])
    mean_b = xb @ np.array([1.15, 1.0, 0.05]) + 0.05 * rng.standard_normal(n)
    ca = np.diag([0.02, 0.05]) ** 2
    cb = np.diag([0.03, 0.1, 0.05]) ** 2
    return noise, (mean_a, noise + xa @ ca @ xa.T), (mean_b, noise + xb @ cb @ xb.T)


def _whitened(noise, truth, alt):
    """The arguments of log_ratio_moments: whitening by the noise's Cholesky factor, coordinates centred on the
    truth's mean."""
    factor = cholesky(noise, lower=True)

    def w(m):
        return solve_triangular(factor, m, lower=True)

    shift = w(alt[0] - truth[0])
    return shift, w(w(truth[1]).T).T, w(w(alt[1]).T).T


def test_expected_log_ratio_and_its_spread_match_monte_carlo():
    noise, a, b = _linear_gaussian_pair()
    shift, sa, sb = _whitened(noise, a, b)
    moments = log_ratio_moments(shift, sa, sb)
    y = multivariate_normal(a[0], a[1]).rvs(size=200_000, random_state=np.random.default_rng(1))
    ratio = multivariate_normal(a[0], a[1]).logpdf(y) - multivariate_normal(b[0], b[1]).logpdf(y)
    se_mean = ratio.std() / math.sqrt(ratio.size)
    assert moments.expected > 1.0  # the pair is not trivially identical
    assert abs(moments.expected - ratio.mean()) < 4 * se_mean
    assert moments.sd == pytest.approx(ratio.std(), rel=0.02)
    # the root-mean-square measurement SE: ||S_a^-1 w - S_b^-1 (w - d)|| in whitened coordinates
    wa = solve_triangular(cholesky(noise, lower=True), (y - a[0]).T, lower=True).T
    g = np.linalg.solve(sa, wa.T).T - np.linalg.solve(sb, (wa - shift).T).T
    assert moments.se == pytest.approx(math.sqrt(np.mean(np.sum(g**2, axis=1))), rel=0.01)


def test_simulated_power_matches_an_independent_simulation_of_the_rule():
    noise, a, b = _linear_gaussian_pair()
    shift, sa, sb = _whitened(noise, a, b)
    power, accuracy = decision_power([np.zeros(shift.size), shift], [sa, sb], 0, min_delta=4.0, se_factor=2.0,
                                     draws=20_000, seed=3)
    # independent: raw-coordinate log densities (scipy), the SE from the whitened gradients
    y = multivariate_normal(a[0], a[1]).rvs(size=40_000, random_state=np.random.default_rng(11))
    ratio = multivariate_normal(a[0], a[1]).logpdf(y) - multivariate_normal(b[0], b[1]).logpdf(y)
    wa = solve_triangular(cholesky(noise, lower=True), (y - a[0]).T, lower=True).T
    se = np.linalg.norm(np.linalg.solve(sa, wa.T).T - np.linalg.solve(sb, (wa - shift).T).T, axis=1)
    reference = np.mean((ratio > 4.0) & (ratio > 2.0 * se))
    assert 0.05 < reference < 0.95  # a pair the rule neither always nor never separates
    tol = 4 * math.sqrt(reference * (1 - reference) * (1 / 20_000 + 1 / 40_000))
    assert abs(power[1] - reference) < tol
    assert math.isnan(power[0]) and accuracy == power[1]  # two hypotheses: accuracy is the pair's power


@pytest.mark.parametrize("distance", [2.0, 3.5, 5.0])
def test_power_of_equal_covariances_is_the_analytic_normal_tail(distance):
    """S_a = S_b = I, shift d: L = |d|^2 / 2 - d'w ~ N(|d|^2 / 2, |d|^2), SE = |d| for every draw."""
    d = np.zeros(30)
    d[:3] = distance / math.sqrt(3.0)
    margin = max(4.0, 2.0 * distance)
    analytic = norm.sf((margin - distance**2 / 2) / distance)
    power, _ = decision_power([np.zeros(30), d], [np.eye(30), np.eye(30)], 0, draws=20_000, seed=0)
    assert abs(power[1] - analytic) < 4 * math.sqrt(analytic * (1 - analytic) / 20_000) + 1e-12
    m = log_ratio_moments(d, np.eye(30), np.eye(30))
    assert m.expected == pytest.approx(distance**2 / 2, rel=1e-12)
    assert m.sd == pytest.approx(distance, rel=1e-12) and m.se == pytest.approx(distance, rel=1e-12)


@pytest.mark.parametrize("offsets", [[1.5], [-1.0, 2.5]])
def test_power_with_truth_offsets_is_the_analytic_normal_tail(offsets):
    """Data from the truth's forward runs at parameter draws: w = o_j + e, S_a = S_b = I, shift d. Then
    L = |d|^2 / 2 - d'(o_j + e) ~ N(|d|^2 / 2 - d'o_j, |d|^2) and SE = |d|: the power is the mean over the draws of
    the normal tails (offsets o_j = c_j d / |d| along the shift, c_j given)."""
    n, distance = 20, 4.0
    unit = np.zeros(n)
    unit[:4] = 0.5
    d = distance * unit
    rows = np.array([c * unit for c in offsets])
    margin = max(4.0, 2.0 * distance)
    analytic = np.mean([norm.sf((margin - (distance**2 / 2 - c * distance)) / distance) for c in offsets])
    power, accuracy = decision_power([np.zeros(n), d], [np.eye(n), np.eye(n)], 0, draws=20_000, seed=2,
                                     truth_offsets=rows)
    assert 0.05 < analytic < 0.95
    assert abs(power[1] - analytic) < 4 * math.sqrt(analytic * (1 - analytic) / 20_000)
    assert accuracy == power[1]


def test_dispersion_corrected_power_matches_a_brute_force_simulation_of_the_rule():
    """The rule with the diagnosis's over-dispersion correction (SE x sqrt(max(1, phi_a, phi_b)), phi_m the mean
    square of w - d_m) on data from truth draws, against an independent simulation with scipy's log densities."""
    noise, a, b = _linear_gaussian_pair()
    shift, sa, sb = _whitened(noise, a, b)
    n = shift.size
    offsets = np.random.default_rng(7).normal(0.0, 1.2, size=(5, n))
    kw = dict(min_delta=4.0, se_factor=2.0, draws=20_000, seed=4, truth_offsets=offsets)
    plain, _ = decision_power([np.zeros(n), shift], [sa, sb], 0, **kw)
    power, _ = decision_power([np.zeros(n), shift], [sa, sb], 0, dispersion=True, **kw)
    rng = np.random.default_rng(13)
    w = offsets[rng.integers(0, 5, 40_000)] + rng.standard_normal((40_000, n))
    ratio = multivariate_normal(np.zeros(n), sa).logpdf(w) - multivariate_normal(shift, sb).logpdf(w)
    se = np.linalg.norm(w @ np.linalg.inv(sa) - (w - shift) @ np.linalg.inv(sb), axis=1)
    phi = np.maximum(np.maximum((w**2).mean(axis=1), ((w - shift) ** 2).mean(axis=1)), 1.0)
    for got, inflation in ((plain, 1.0), (power, np.sqrt(phi))):
        reference = np.mean((ratio > 4.0) & (ratio > 2.0 * se * inflation))
        assert 0.05 < reference < 0.95
        assert abs(got[1] - reference) < 4 * math.sqrt(reference * (1 - reference) * (1 / 20_000 + 1 / 40_000))
    assert power[1] < plain[1] - 0.05  # the correction matters on these data


def test_truth_offsets_of_the_wrong_shape_are_rejected():
    with pytest.raises(ParameterError, match="truth_offsets"):
        decision_power([np.zeros(3), np.ones(3)], [np.eye(3)] * 2, 0, draws=100, truth_offsets=np.zeros((2, 4)))


# -- design space -------------------------------------------------------------------------------------------------

_TOY = {"name": "toy", "slugs": [{"name": "W", "pv": 0.3, "salinity_ppm": 9400},
                                 {"name": "P", "pv": 1.0, "salinity_ppm": 9400, "polymer_ppm": 2000},
                                 {"name": "C", "pv": 0.5, "salinity_ppm": 9400}]}


def test_design_space_holds_every_kind_with_the_stated_rates():
    designs = design_space(_TOY, 0.25)
    assert {d.kind for d in designs} == set(DESIGN_KINDS)
    assert len({d.label for d in designs}) == len(designs)
    ref = as_schedule(_TOY)
    for d in designs:
        if d.kind == "rate_step":  # same injection, the polymer slug split at other rates
            assert d.schedule.total_pv == pytest.approx(ref.total_pv, abs=1e-12)
            parts = [s for s in d.schedule.slugs if s.polymer_ppm > 0]
            assert sum(s.pv for s in parts) == pytest.approx(1.0, abs=1e-12)
            assert parts[0].rate_ml_min == 0.25 and all(s.polymer_ppm == 2000 for s in parts)
    staircase = [d for d in designs if d.kind == "rate_step" and "staircase" in d.label][0]
    assert [s.rate_ml_min for s in staircase.schedule.slugs if s.polymer_ppm > 0] == [0.25, 0.125, 0.5, 1.0]
    flush = [d for d in designs if d.kind == "post_flush"][0]
    assert flush.schedule.total_pv == pytest.approx(ref.total_pv + 2.0, abs=1e-12)
    assert [d.kind for d in design_space("BCF1", 0.25, kinds=["repeat"])] == ["repeat"]


def test_design_space_rejects_bad_settings_before_any_work():
    with pytest.raises(ParameterError, match="rate_factors"):
        design_space(_TOY, 0.25, rate_factors=(2.0, -1.0))
    with pytest.raises(ParameterError, match="unknown kind"):
        design_space(_TOY, 0.25, kinds=["tracer"])
    with pytest.raises(ParameterError, match="base_rate_ml_min"):
        design_space(_TOY, 0.0)
    with pytest.raises(ParameterError, match="rate_ml_min"):  # 4 x 400 ml/min leaves QINJ's bounds
        design_space(_TOY, 400.0)


def test_schedule_toml_round_trip(tmp_path):
    sched = as_schedule({"name": 'odd "name"', "slugs": [
        {"name": "W", "pv": 0.1 + 0.2, "salinity_ppm": 9400.0},
        {"name": "P@2", "pv": 1.0 / 3.0, "salinity_ppm": 9400.0, "polymer_ppm": 1234.5, "rate_ml_min": 0.6}]})
    path = tmp_path / "s.toml"
    path.write_text(schedule_toml(sched))
    assert read_schedule_file(path) == sched


# -- the rate-step toy: shear thinning against a Newtonian viscosity law ------------------------------------------


@pytest.fixture(scope="module")
def toy():
    """A short polymer flood (12 cells) with Meter shear thinning; two hypotheses calibrated on it: shear thinning
    with its viscosity law, and no shear thinning with a (lower) viscosity law -- alike at the reference rate."""
    effects = {"shear_thinning": 1.0, "permeability_reduction": 0.0}
    data = make_coreflood(_TOY, {}, effects=effects, noise=NoiseModel.random_only(), seed=3, cells=12,
                          experiment="toy")
    [exp] = load_experiments([data], 0.1)
    params = {"AP1": [1.0, 60.0], "AP3": [10.0, 600.0]}
    bases = {"shear_thinning": BaseModel.from_mapping({"cells": 12, "effects": effects, "parameters": params}),
             "viscosity": BaseModel.from_mapping({"cells": 12, "effects": {**effects, "shear_thinning": 0.0},
                                                  "parameters": params})}
    layout = make_layout([exp], ["dp", "oil_cut"])
    fits = {name: fit(Predictor(b, [exp]), layout, [b.default_unit()]) for name, b in bases.items()}
    table = rank_designs(hypotheses_from_fits(fits, bases=bases), bases["viscosity"], exp,
                         design_space(exp.schedule, 0.25), draws=2000)
    return exp, fits, layout, table, bases


def test_toy_hypotheses_agree_on_the_reference_flood(toy):
    _, fits, layout, _, _ = toy
    dof = layout.size - 2
    for f in fits.values():  # both fit the reference flood to the noise level
        assert f.chi2 < dof + 3 * math.sqrt(2 * dof)


def test_rate_steps_rank_first_and_separate_the_toy(toy):
    _, _, _, table, _ = toy
    kinds = list(table["kind"].values)
    n_rate = kinds.count("rate_step")
    assert kinds[:n_rate] == ["rate_step"] * n_rate  # every polymer-slug rate step above every other design
    assert float(table["worst_accuracy"][0]) > 0.95
    repeat = table.isel(design=kinds.index("repeat"))
    assert float(repeat["worst_accuracy"]) < 0.5  # a replicate of the reference flood does not separate them
    # the separation of the best design comes from the parts of the polymer slug injected at a changed rate
    best = table.isel(design=0)
    schedule = as_schedule(json.loads(str(best["schedule"].values)))
    changed = {s.name for s in schedule.slugs if s.rate_ml_min not in (None, 0.25)}
    shares = json.loads(str(best["separation_by_slug"].values))
    assert sum(shares.get(n, 0.0) for n in changed) > 0.5


def test_monte_carlo_parameter_spread_keeps_the_ranking(toy):
    exp, fits, _, _, bases = toy
    designs = design_space(exp.schedule, 0.25, kinds=["repeat", "rate_step"])
    table = rank_designs(hypotheses_from_fits(fits, bases=bases), bases["viscosity"], exp, designs, draws=1000,
                         parameter_draws=12, truth_draws=12)
    assert list(table["kind"].values[:-1]) == ["rate_step"] * (len(designs) - 1)
    assert table.attrs["parameter_uncertainty_method"] == "Monte Carlo over 12 parameter draws"
    # forward runs: per hypothesis and design, the fit plus 12 draws (the truth's data reuse the spread's draws)
    assert table.attrs["forward_runs"] == 2 * len(designs) * 13


def test_numerical_error_term_on_the_designs(toy):
    """The diagnosis's numerical-error term in the designer's error model: at scale 0 the ranking is the one
    without it; at a scale that makes the numerics dominate, the designs separate less; its runs are counted (per
    design, the base point at its own numerics and at each alternative)."""
    exp, fits, _, _, bases = toy
    hypotheses = hypotheses_from_fits(fits, bases=bases)
    designs = design_space(exp.schedule, 0.25, kinds=["repeat", "rate_step"])[:3]
    base = bases["viscosity"]
    base_fit = fits["viscosity"]
    plain = rank_designs(hypotheses, base, exp, designs, draws=500, truth_draws=5)
    zero = rank_designs(hypotheses, base, exp, designs, draws=500, truth_draws=5,
                        numerical=NumericalTerm(base_fit, DEFAULT_VARIANTS, 0.0))
    assert np.array_equal(plain["accuracy"].values, zero["accuracy"].values)
    assert zero.attrs["numerical_error"] == "none" and zero.attrs["forward_runs"] == plain.attrs["forward_runs"]
    big = rank_designs(hypotheses, base, exp, designs, draws=500, truth_draws=5,
                       numerical=NumericalTerm(base_fit, DEFAULT_VARIANTS, 30.0))
    assert big.attrs["numerical_error"].startswith("the diagnosis's numerical-error term, scale 30")
    assert big.attrs["forward_runs"] == plain.attrs["forward_runs"] + len(designs) * (1 + len(DEFAULT_VARIANTS))
    by_label = {str(x): i for i, x in enumerate(plain["label"].values)}
    for j, label in enumerate(big["label"].values):
        i = by_label[str(label)]
        assert float(big["worst_expected_log_ratio"][j]) < float(plain["worst_expected_log_ratio"][i])
    with pytest.raises(ParameterError, match="numerical.scale"):
        rank_designs(hypotheses, base, exp, designs, numerical=NumericalTerm(base_fit, DEFAULT_VARIANTS, -1.0))


def test_predicted_accuracy_holds_on_simulated_lab_corefloods(toy):
    """End to end: lab-like corefloods of the design (make_coreflood: the measurement chain's own random errors),
    scored by the diagnosis's held-out predictive densities and decision rule."""
    exp, fits, _, table, bases = toy
    hypotheses = hypotheses_from_fits(fits, bases=bases)
    best = realised_accuracy(table, hypotheses, bases["viscosity"], exp, rank=1, seeds=6)
    assert np.all(best.values == 1.0)  # predicted 1.00 / 1.00
    repeat = int(table["rank"].values[list(table["kind"].values).index("repeat")])
    assert np.all(table["accuracy"].values[repeat - 1] < 0.05)
    assert np.all(realised_accuracy(table, hypotheses, bases["viscosity"], exp, rank=repeat, seeds=6).values <= 1 / 6)


def test_ranked_table_schema(toy):
    _, _, _, table, _ = toy
    n = table.sizes["design"]
    assert table["expected_log_ratio"].dims == ("design", "truth", "alternative")
    assert table["accuracy"].dims == ("design", "truth")
    assert list(table["truth"].values) == ["shear_thinning", "viscosity"]
    for name, unit in (("expected_log_ratio", "1"), ("log_ratio_sd", "1"), ("decision_margin", "1"),
                       ("power", "1"), ("accuracy", "1"), ("worst_accuracy", "1"), ("mean_accuracy", "1"),
                       ("worst_power", "1"), ("worst_expected_log_ratio", "1"), ("total_pv", "1"),
                       ("duration", "h"), ("rank", "1")):  # log ratios in nats and pore volumes are numbers
        assert table[name].attrs["units"] == unit, name
    assert all("nats" in table[n].attrs["long_name"] for n in ("expected_log_ratio", "log_ratio_sd",
                                                              "decision_margin", "worst_expected_log_ratio"))
    assert list(table["rank"].values) == list(range(1, n + 1))
    acc = table["worst_accuracy"].values
    assert np.all(np.diff(acc) <= 1e-12)  # ranked by the worst hypothesis's accuracy
    assert np.all(np.isnan(np.diagonal(table["power"].values, axis1=1, axis2=2)))
    assert np.all((table["power"].values[:, [0, 1], [1, 0]] >= 0) & (table["power"].values[:, [0, 1], [1, 0]] <= 1))
    # duration of the repeat: 1.8 PV of the core's pore volume at 0.25 ml/min
    repeat = table.isel(design=list(table["kind"].values).index("repeat"))
    exp = toy[0]
    assert float(repeat["duration"]) == pytest.approx(1.8 * exp.pore_volume_ml / 0.25 / 60.0, rel=1e-12)
    assert table.attrs["base_rate_ml_min"] == 0.25 and table.attrs["noise_model_source"] == "reference data"


def test_truth_dispersion_of_a_repeat_is_bounded_by_the_calibrated_parameters(toy):
    """On a replicate of the calibration flood the truth's parameter draws move its whitened prediction by
    ``A dz`` with ``E||A dz||^2 = tr(J_w C J_w') = sum_i l_i / (l_i + 1/tau^2) < q`` (``l_i`` the eigenvalues of
    ``J_w' J_w``, ``q`` the calibrated parameters): ``truth_dispersion - 1`` is at most about ``q / n``."""
    _, fits, _, table, _ = toy
    repeat = table.isel(design=list(table["kind"].values).index("repeat"))
    n = int(repeat["n_points"])
    assert table["truth_dispersion"].attrs["units"] == "1"
    for name, f in fits.items():
        lam = np.linalg.eigvalsh(f.jacobian.T @ f.jacobian)
        bound = float(np.sum(lam / (lam + 1 / 0.5**2)))
        assert bound < f.z.size
        assert 1.0 + 0.1 * bound / n <= float(repeat["truth_dispersion"].sel(truth=name)) <= 1.0 + 3.0 * bound / n
    assert table.attrs["truth_draws"] == 20 and table.attrs["dispersion_correction"] == 1


def test_proposal_files_round_trip(toy, tmp_path):
    _, _, _, table, _ = toy
    paths = write_proposal(table, tmp_path / "next")
    best = as_schedule(json.loads(str(table["schedule"].values[0])))
    assert read_schedule_file(paths["schedule"]) == best
    assert any(s.rate_ml_min is not None for s in best.slugs)
    rationale = json.loads(paths["rationale"].read_text())
    assert rationale["label"] == str(table["label"].values[0])
    assert rationale["worst_accuracy"] == float(table["worst_accuracy"][0])
    assert {(p["truth"], p["alternative"]) for p in rationale["pairs"]} == {("shear_thinning", "viscosity"),
                                                                         ("viscosity", "shear_thinning")}
    with pytest.raises(ParameterError, match="rank"):
        write_proposal(table, tmp_path / "x", rank=0)


def test_proposal_as_a_study_experiment(toy, tmp_path):
    """The best design appended to (a copy of) the bundled study as a predict-only experiment loads back with the
    design's schedule and the toy coreflood's core, rate and measurement chain."""
    exp, _, _, table, _ = toy
    paths = write_proposal(table, tmp_path)
    text, missing = study_experiment_toml("next_experiment", paths["schedule"].name, exp.core, exp.measurement,
                                          exp.name)
    stated = {"LENGTH": "core.length", "DIAMETER": "core.diameter", "PORO": "core.porosity",
              "PERM": "core.permeability", "SWI": "core.swi", "QINJ": "rate"}
    assert sorted(missing) == sorted(f for p, f in stated.items() if p not in exp.core)
    core = {"PERM": 700.0} | exp.core  # the core's permeability, which the toy's file does not state
    text, missing = study_experiment_toml("next_experiment", paths["schedule"].name, core, exp.measurement)
    assert missing == []
    source = bundled_study_path()
    for f in source.parent.glob("BCF*.nc"):
        shutil.copy(f, tmp_path / f.name)
    study_file = tmp_path / "study.toml"
    study_file.write_text(source.read_text() + "\n" + text)
    proposed = load_study(study_file).experiment("next_experiment")
    assert proposed.role == "predict" and proposed.data is None
    assert proposed.schedule.slugs == as_schedule(json.loads(str(table["schedule"].values[0]))).slugs
    params = proposed.model_params()
    for p in stated:
        assert params[p] == pytest.approx(core[p], rel=1e-12)
    assert proposed.measurement == exp.measurement


def test_rank_designs_rejects_bad_input(toy):
    exp, fits, _, _, bases = toy
    base = bases["viscosity"]
    one = [Hypothesis("a", fits["viscosity"])]
    with pytest.raises(ParameterError, match="at least two hypotheses"):
        rank_designs(one, base, exp)
    two = [Hypothesis("a", fits["viscosity"]), Hypothesis("b", fits["shear_thinning"], base=bases["shear_thinning"])]
    with pytest.raises(ParameterError, match="not measured"):
        rank_designs(two, base, replace(exp, observed={"dp": exp.observed["dp"]}), variables=("oil_cut",))
    with pytest.raises(ParameterError, match="criterion"):
        rank_designs(two, base, exp, criterion="best")
    # without parameter uncertainty (no covariance): the rate steps still come first
    plain = rank_designs(two, base, exp, design_space(exp.schedule, 0.25, kinds=["repeat", "rate_step"]),
                         draws=500)
    assert plain["kind"].values[0] == "rate_step" and json.loads(plain.attrs["parameter_uncertainty"]) == {
        "a": False, "b": False}
    with pytest.raises(ParameterError, match="covariance"):
        Hypothesis("c", fits["viscosity"], np.eye(3))


# -- after a diagnosis: the ambiguity set's refits -> the proposal files (spflow diagnose) -------------------------


def test_competing_fits_take_the_last_step_that_refitted_every_member():
    from types import SimpleNamespace

    from spflow.plugins.gap.next_after_diagnosis import competing_fits

    steps = [SimpleNamespace(fits={"a": 1, "b": 2, "c": 3}), SimpleNamespace(fits={"a": 10, "c": 30})]
    diag = lambda verdict, ambiguity, closers=(): SimpleNamespace(  # noqa: E731
        verdict=verdict, ambiguity=list(ambiguity), closers=list(closers), steps=steps, base_fit=0)
    assert competing_fits(diag("ambiguous", ["a", "b"])) == {"a": 1, "b": 2}
    assert competing_fits(diag("ambiguous", ["a", "c"])) == {"a": 10, "c": 30}
    assert competing_fits(diag("effect", ["a"])) == {}  # nothing to separate
    assert competing_fits(diag("none", [])) == {}


def test_competing_fits_of_an_unattributed_gap_are_the_base_against_its_closers():
    """Weakly identified: candidates close the calibration gap but none is declared. The base model itself is a
    hypothesis, against the first step's refits of at most MAX_UNATTRIBUTED closers (best held-out score first)."""
    from types import SimpleNamespace

    from spflow.plugins.gap.next_after_diagnosis import BASE_HYPOTHESIS, MAX_UNATTRIBUTED, competing_fits

    fits = {name: i + 1 for i, name in enumerate("abcde")}
    steps = [SimpleNamespace(fits=fits), SimpleNamespace(fits={"a": 10})]
    closers = ["d", "a", "e", "b"]
    got = competing_fits(SimpleNamespace(verdict="unattributed", ambiguity=[], closers=closers, steps=steps,
                                         base_fit=0))
    assert MAX_UNATTRIBUTED == 3
    assert got == {BASE_HYPOTHESIS: 0, "d": 4, "a": 1, "e": 5}
    assert list(got) == [BASE_HYPOTHESIS, "d", "a", "e"]
    # an unattributed verdict without closers (a gap only the omnibus test finds, which no candidate closes) and an
    # out-of-catalogue verdict propose nothing
    for verdict, cl in (("unattributed", []), ("out_of_catalogue", ["a", "b"])):
        assert competing_fits(SimpleNamespace(verdict=verdict, ambiguity=[], closers=cl, steps=steps,
                                              base_fit=0)) == {}


def test_hypotheses_source_names_the_closers_left_out():
    from types import SimpleNamespace

    from spflow.plugins.gap.next_after_diagnosis import hypotheses_source

    five = SimpleNamespace(verdict="unattributed", closers=["d", "a", "e", "b", "c"])
    assert hypotheses_source(five).endswith("the first 3 of the 5 candidates that close it (best held-out score "
                                            "first); left out: b, c")
    assert "left out" not in hypotheses_source(SimpleNamespace(verdict="unattributed", closers=["a", "b"]))
    assert hypotheses_source(SimpleNamespace(verdict="ambiguous", closers=[])) == "the diagnosis's final ambiguity set"


def test_accuracy_caveat_only_after_an_unattributed_verdict():
    from types import SimpleNamespace

    from spflow.plugins.gap.next_after_diagnosis import accuracy_caveat

    assert "pin weakly" in accuracy_caveat(SimpleNamespace(verdict="unattributed"))
    assert accuracy_caveat(SimpleNamespace(verdict="ambiguous")) is None


def test_proposal_after_an_ambiguous_diagnosis(toy, tmp_path, monkeypatch):
    """An ambiguous verdict between the toy's two hypotheses: the proposal is a rate step (the only design the
    physics lets separate them), written as a schedule file, a rationale and a study experiment that loads."""
    from types import SimpleNamespace

    import spflow.plugins.gap.next_after_diagnosis as nad
    from spflow.plugins.gap.diagnosis import Options

    exp, fits, _, _, bases = toy
    # the toy's hypotheses differ by their base model (the diagnosis's by their candidate effect): pass the bases
    monkeypatch.setattr(nad, "hypotheses_from_fits", lambda f: hypotheses_from_fits(f, bases=bases))
    diag = SimpleNamespace(verdict="ambiguous", closers=[], ambiguity=["shear_thinning", "viscosity"],
                           steps=[SimpleNamespace(fits=fits)],
                           calibration=[exp], base=bases["viscosity"], options=Options(variables=("dp", "oil_cut")),
                           base_fit=fits["viscosity"], numerical_scale=None)  # (no numerical-error term)
    proposal = nad.propose_next_experiment(diag, tmp_path)
    assert proposal.summary["kind"] == "rate_step" and proposal.summary["worst_accuracy"] > 0.95
    assert read_schedule_file(proposal.files["schedule"]) == as_schedule(proposal.summary["schedule"])
    assert any("next experiment" in line and "rate" in line for line in proposal.lines())
    assert "the diagnosis's final ambiguity set" in proposal.lines()[0]
    assert not any("caution" in line for line in proposal.lines())
    assert "accuracy_caveat" not in json.loads(proposal.files["rationale"].read_text())["assumptions"]
    # with a caveat (after an unattributed verdict) the rationale records it and the CLI prints it
    proposal.table.attrs["accuracy_caveat"] = "far lower"
    summary = proposal_summary(proposal.table)
    assert summary["assumptions"]["accuracy_caveat"] == "far lower"
    assert "  caution: far lower" in nad.NextExperiment(proposal.table, summary, proposal.files).lines()
    assert json.loads(proposal.files["rationale"].read_text())["assumptions"]["hypotheses_source"] == \
        "the diagnosis's final ambiguity set"
    # the predict-role study experiment names the schedule file (its loading: test_proposal_as_a_study_experiment)
    text = proposal.files["study_experiment"].read_text()
    assert 'role = "predict"' in text and f'schedule = "{proposal.files["schedule"].name}"' in text
