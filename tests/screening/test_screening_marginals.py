"""Screening under the inputs' marginals (issue #24): Sobol' indices and Morris effects of designs drawn on the unit
hypercube and mapped through each marginal's quantile function.

References computed here: the Sobol' indices of a linear model y = Σ a_i x_i, S_i = S_i^T = a_i² Var(x_i) /
Σ_j a_j² Var(x_j), with the variances of the normal, beta and truncated normal laws written out by hand; Morris mu*
of a linear model from the design itself (|a_i Δx_i| / Delta per one-at-a-time step); the designs of uniform
marginals against SALib's own box designs, bit for bit; points on the cube's faces under unbounded and bounded laws
against scipy's quantiles; and, on the forward model, a screening stage whose space
records uniform marginals against one that records none, bit for bit.
"""

import numpy as np
import pytest
from scipy import special, stats

from spflow.core.errors import ParameterError
from spflow.core.stage import StageContext
from spflow.plugins.design.parameter_space import ParameterSpace
from spflow.plugins.forward.stage import Forward
from spflow.plugins.screening.morris import morris_indices, morris_sample
from spflow.plugins.screening.salib_glue import salib_design
from spflow.plugins.screening.selected_space import SelectedSpace
from spflow.plugins.screening.sobol import sobol_indices, sobol_sample
from spflow.plugins.screening.sobol_screening import SobolScreening
from spflow.plugins.surrogates.input_marginals import Beta, Normal, TruncatedNormal, Uniform, marginal_variables

NAMES = ["x1", "x2", "x3", "x4"]
A = np.array([1.0, -2.0, 3.0, 0.5])


def _truncnorm_variance(mean, std, lower, upper):
    """Variance of N(mean, std²) truncated to [lower, upper] (Johnson, Kotz & Balakrishnan, Eq. 13.134)."""
    a, b = (lower - mean) / std, (upper - mean) / std
    z = special.ndtr(b) - special.ndtr(a)
    pa, pb = np.exp(-0.5 * a * a) / np.sqrt(2 * np.pi), np.exp(-0.5 * b * b) / np.sqrt(2 * np.pi)
    return std**2 * (1 + (a * pa - b * pb) / z - ((pa - pb) / z) ** 2)


def _linear_reference(variances):
    share = A**2 * np.asarray(variances)
    return share / share.sum()


LAWS = [Normal(1.0, 0.5), Beta(2.0, 5.0, 0.0, 2.0), TruncatedNormal(0.5, 1.0, 0.0, 1.0), Uniform(-1.0, 3.0)]
# by hand: std², αβ/((α+β)²(α+β+1)) (u−l)², the truncated normal's, (u−l)²/12
VARIANCES = [0.25, 2 * 5 / (7**2 * 8) * 4.0, _truncnorm_variance(0.5, 1.0, 0.0, 1.0), 16 / 12]


def test_sobol_indices_of_a_linear_model_under_normal_beta_and_truncated_normal_inputs():
    lower, upper = np.array([-np.inf, 0.0, 0.0, -1.0]), np.array([np.inf, 2.0, 1.0, 3.0])
    x = sobol_sample(NAMES, lower, upper, 2**13, seed=1, inputs=LAWS)
    for j, law in enumerate(LAWS):  # the design is drawn from the marginals (scipy's cdfs)
        assert stats.kstest(x[:6 * 2**13:6, j], law.frozen().cdf).pvalue > 0.01
    out = sobol_indices(x @ A, NAMES, seed=2)
    reference = _linear_reference(VARIANCES)
    for key in ("S1", "ST"):
        error = np.abs(out[key].values[0] - reference)
        # within 2 bootstrap half-widths (95 %: about 4 standard errors) and 0.003
        np.testing.assert_array_less(error, np.maximum(2 * out[f"{key}_conf"].values[0], 1e-3))
        assert error.max() < 0.003
    # uniform laws on the supports of x2, x3 would give other indices (so the test sees the marginals)
    boxed = _linear_reference([0.25, 4 / 12, 1 / 12, 16 / 12])
    assert np.abs(out["S1"].values[0] - boxed).max() > 0.2


def test_a_design_point_on_a_face_is_finite_under_an_unbounded_law_and_unmoved_under_a_bounded_one():
    # a sampler whose points lie on the faces 0 and 1 (SALib's scrambled Sobol' points can be exactly 0; Morris levels
    # are 0 and 1): a normal marginal's quantile is infinite there, a beta's and a uniform's are the support's ends
    faces = np.array([[0.0, 0.0, 0.0], [1.0, 1.0, 1.0], [0.25, 0.5, 0.75]])
    laws = [Normal(1.0, 0.5), Beta(2.0, 5.0, 0.0, 2.0), Uniform(-1.0, 3.0)]
    x = salib_design(lambda problem: faces.copy(), NAMES[:3], None, None, inputs=laws)
    edge = 0.5**31  # half a cell of 30-bit Sobol' points
    np.testing.assert_allclose(x[:2, 0], stats.norm(1.0, 0.5).ppf([edge, 1.0 - edge]), rtol=1e-12)
    assert np.isfinite(x).all()
    np.testing.assert_array_equal(x[:2, 1], [0.0, 2.0])
    np.testing.assert_array_equal(x[:2, 2], [-1.0, 3.0])
    np.testing.assert_allclose(x[2], [stats.norm(1.0, 0.5).ppf(0.25), stats.beta(2.0, 5.0, scale=2.0).ppf(0.5), 2.0],
                               rtol=1e-10)


def test_uniform_marginals_give_salibs_box_design_bit_for_bit():
    from SALib.sample import morris as salib_morris
    from SALib.sample import sobol as salib_sobol

    lower, upper = np.array([0.02, 1.5, -3.0]), np.array([0.05, 3.0, 7.5])
    uniform = [Uniform(lo, hi) for lo, hi in zip(lower, upper)]
    problem = {"num_vars": 3, "names": NAMES[:3], "bounds": np.column_stack([lower, upper]).tolist()}
    for seed in (0, 7):
        box = salib_sobol.sample(problem, 64, calc_second_order=True, scramble=True, seed=seed)
        np.testing.assert_array_equal(sobol_sample(NAMES[:3], lower, upper, 64, calc_second_order=True, seed=seed,
                                                   inputs=uniform), box)
        np.testing.assert_array_equal(sobol_sample(NAMES[:3], lower, upper, 64, calc_second_order=True, seed=seed),
                                      box)
        box = salib_morris.sample(problem, 10, num_levels=4, seed=seed)
        np.testing.assert_array_equal(morris_sample(NAMES[:3], lower, upper, 10, seed=seed, inputs=uniform), box)


def test_morris_effects_under_marginals_are_per_step_of_the_cdf():
    laws = [TruncatedNormal(0.5, 0.2, 0.0, 2.0), Beta(0.5, 3.0, 1.0, 4.0), Uniform(0.0, 10.0)]
    a = np.array([2.0, -1.0, 0.3])
    lower, upper = np.array([0.0, 1.0, 0.0]), np.array([2.0, 4.0, 10.0])
    x = morris_sample(NAMES[:3], lower, upper, 40, levels=4, seed=5, inputs=laws)
    # the grid is the marginals' quantiles at 0, 1/3, 2/3, 1 (scipy's ppf)
    for j, law in enumerate(laws):
        levels = law.frozen().ppf(np.arange(4) / 3)
        nearest = np.abs(x[:, j, None] - levels).argmin(axis=1)
        np.testing.assert_allclose(x[:, j], levels[nearest], rtol=1e-12)
        assert set(nearest.tolist()) == {0, 1, 2, 3}
    out = morris_indices(x, x @ a, NAMES[:3], lower, upper, levels=4, seed=6)
    # by hand: each trajectory changes one column per step; |EE| = |a_i Δx_i| / Delta, Delta = 4 / (2 (4 - 1))
    delta = 4 / 6
    steps = np.diff(x.reshape(40, 4, 3), axis=1).reshape(-1, 3)
    moved = np.abs(steps) > 0
    assert (moved.sum(axis=1) == 1).all()
    mu_star = [np.mean(np.abs(a[j] * steps[moved[:, j], j]) / delta) for j in range(3)]
    np.testing.assert_allclose(out["mu_star"].values[0], mu_star, rtol=1e-12)
    # a uniform input's effect is a_i (upper - lower) whatever the step
    assert out["mu_star"].values[0, 2] == pytest.approx(0.3 * 10.0, rel=1e-12)


# -- the screening stage on the forward model ---------------------------------------------------------------------

CTX = StageContext("screening", verbose=False)
RANGES = {"HBNC70": [0.02, 0.05], "E2C": [1.5, 3.0]}
STAGE = {"samples": 4, "mode": "joint", "cells": 30, "seed": 3, "threshold": 0.05}


@pytest.fixture(scope="module")
def space():
    return ParameterSpace(names=list(RANGES), ranges=RANGES).run(CTX)


def _with(space, laws):
    return space.assign(marginal_variables(laws))


def _run_recording_designs(space, monkeypatch):
    designs = []
    original = Forward.run

    def recording(self, ctx, design):
        designs.append(design["values"].values.copy())
        return original(self, ctx, design=design)

    monkeypatch.setattr(Forward, "run", recording)
    return SobolScreening(**STAGE).run(CTX, space=space), designs[-1]


def test_stage_with_uniform_marginals_is_bit_identical_to_the_box(space, monkeypatch):
    box, box_design = _run_recording_designs(space, monkeypatch)
    laws = [Uniform(*RANGES[n]) for n in RANGES]
    marg, marg_design = _run_recording_designs(_with(space, laws), monkeypatch)
    np.testing.assert_array_equal(marg_design, box_design)
    for key in ("S1", "ST", "S1_conf", "ST_conf", "variance", "score"):
        np.testing.assert_array_equal(marg[key].values, box[key].values)
    assert "uniform" in box.attrs["marginals"] and "distribution" not in box
    assert marg["distribution"].values.tolist() == ["uniform", "uniform"]


def test_stage_draws_the_design_from_the_spaces_marginals_and_records_them(space, monkeypatch, capsys):
    laws = [TruncatedNormal(0.03, 0.005, *RANGES["HBNC70"]), Beta(2.0, 3.0, *RANGES["E2C"])]
    _, box_design = _run_recording_designs(space, monkeypatch)
    out, design = _run_recording_designs(_with(space, laws), monkeypatch)
    # the same unit-hypercube points, now through the laws' quantile functions (scipy's ppf of the box's fractions)
    lo, hi = np.array([r[0] for r in RANGES.values()]), np.array([r[1] for r in RANGES.values()])
    u = (box_design - lo) / (hi - lo)
    np.testing.assert_allclose(design[:, 0], stats.truncnorm(-2, 4, loc=0.03, scale=0.005).ppf(u[:, 0]), rtol=1e-9)
    np.testing.assert_allclose(design[:, 1], stats.beta(2.0, 3.0, loc=1.5, scale=1.5).ppf(u[:, 1]), rtol=1e-9)
    assert out["distribution"].values.tolist() == ["truncated_normal", "beta"]
    assert "HBNC70 ~ TruncatedNormal(" in out.attrs["marginals"]
    reduced = SelectedSpace().run(CTX, screening=out)
    kept = [str(n) for n in reduced["param"].values]
    assert reduced["distribution"].values.tolist() == [out["distribution"].sel(param=n).item() for n in kept]
    assert reduced.attrs["distribution"].startswith("independent, per parameter")
    SobolScreening(**STAGE).run(StageContext("shown", verbose=True), space=_with(space, laws))
    assert "E2C ~ Beta(alpha=2, beta=3, lower=1.5, upper=3)" in capsys.readouterr().err


def test_a_marginal_off_the_spaces_range_is_refused_before_any_run(space, monkeypatch):
    monkeypatch.setattr(Forward, "run", lambda *a, **k: pytest.fail("ran the forward model"))
    bad = _with(space, [Uniform(0.0, 0.05), Uniform(*RANGES["E2C"])])
    with pytest.raises(ParameterError, match="stage 'sobol_screening': parameter 'HBNC70' of the space"):
        SobolScreening(**STAGE).run(CTX, space=bad)
