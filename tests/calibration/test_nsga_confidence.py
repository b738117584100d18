"""Noise-consistent ranges of the NSGA-II history match: the archive of evaluated designs, the likelihood-ratio
region against the analytic confidence ellipsoid of a linear-Gaussian model and its coverage over noise draws, the
measurement model carried by the observations stage, and the stage's new outputs."""

import itertools
from dataclasses import replace

import numpy as np
import xarray as xr
import pytest
from pymoo.core.problem import Problem
from pymoo.optimize import minimize
from scipy import stats
from test_nsga_stage import CTX, TABLE_3_2, Z_A, _linear_problem, _small_run
from test_nsga_stage import toy_kind_registered  # noqa: F401  (autouse fixture: registers the toy surrogate kind)

from spflow.core.errors import ParameterError
from spflow.io import load_coreflood
from spflow.plugins.calibration.nsga2_algorithm import thesis_nsga2
from spflow.plugins.calibration.nsga2_confidence import region_extent, whitened_chi2
from spflow.plugins.calibration.nsga2_history import CalibrationHistory
from spflow.plugins.calibration.nsga2_stage import NSGA2Calibration
from spflow.plugins.design.parameter_space import ParameterSpace
from spflow.plugins.gap.error_model import BlockErrorModel
from spflow.plugins.gap.observed import load_experiments, observed_experiment
from spflow.plugins.observations import Observations, at_core_outlet
from spflow.synthetic import NoiseModel

LEVEL = 0.95


class _Recording(Problem):
    """Two quadratic objectives on [0, 1]^3 that remember every point pymoo asks them to evaluate."""

    def __init__(self):
        super().__init__(n_var=3, n_obj=2, xl=0.0, xu=1.0)
        self.seen = []

    def _evaluate(self, x, out, *args, **kwargs):
        self.seen.append(x.copy())
        out["F"] = np.c_[np.sum(x**2, axis=1), np.sum((x - 1) ** 2, axis=1)]


def test_archive_holds_every_evaluated_design_once():
    problem, pop, generations = _Recording(), 16, 7
    history = CalibrationHistory(generations, 100, 0.0, [1], lambda x: np.zeros((len(x), 1, 1)))
    minimize(problem, thesis_nsga2(pop_size=pop), ("n_gen", generations), seed=4, callback=history)
    assert history.archive.shape == (pop + (generations - 1) * pop, 3)
    np.testing.assert_array_equal(history.archive, np.concatenate(problem.seen))


# --- a linear-Gaussian model: y = A ξ + b + e, with one white, one AR(1) and one random-walk error block ---------

def _covariances():
    """Dense covariances of the three blocks, written from their definitions (not from the whitening code)."""
    white = 0.5**2 * np.eye(12)
    t = np.arange(15)
    ar1 = 0.3**2 * 0.7 ** np.abs(t[:, None] - t[None, :])
    steps = np.linspace(0.1, 0.2, 10) ** 2  # e_t = e_{t-1} + a_t w_t: Cov(e_i, e_j) = Σ_{k <= min(i, j)} a_k²
    walk = np.cumsum(steps)[np.minimum.outer(np.arange(10), np.arange(10))]
    return [white, ar1, walk]


def _models():
    return [BlockErrorModel(np.full(12, 0.5), 0.0), BlockErrorModel(np.full(15, 0.3), 0.7),
            BlockErrorModel(np.linspace(0.1, 0.2, 10), 1.0)]


class _LinearGaussian:
    truth = np.array([0.3, -0.2])

    def __init__(self):
        rng = np.random.default_rng(12)
        self.cov = _covariances()
        self.A = [rng.standard_normal((c.shape[0], 2)) * s for c, s in zip(self.cov, (1.0, 0.4, 0.3))]
        self.b = [rng.standard_normal(c.shape[0]) for c in self.cov]
        info = sum(a.T @ np.linalg.solve(c, a) for a, c in zip(self.A, self.cov))
        self.C = np.linalg.inv(info)  # covariance of the generalised-least-squares estimate
        self.q = stats.chi2.ppf(LEVEL, df=2)
        self.half = np.sqrt(self.q * np.diag(self.C))  # projections of the ellipsoid Δχ² <= q

    def data(self, rng):
        return [a @ self.truth + b + np.linalg.cholesky(c) @ rng.standard_normal(c.shape[0])
                for a, b, c in zip(self.A, self.b, self.cov)]

    def gls(self, y):
        rhs = sum(a.T @ np.linalg.solve(c, yb - b) for a, b, c, yb in zip(self.A, self.b, self.cov, y))
        return self.C @ rhs

    def chi2_dense(self, x, y):
        return sum(float((a @ x + b - yb) @ np.linalg.solve(c, a @ x + b - yb))
                   for a, b, c, yb in zip(self.A, self.b, self.cov, y))

    def archive(self, rng, n, width):
        return self.truth + width * self.half * rng.uniform(-1.0, 1.0, (n, 2))

    def chi2(self, points, y):
        return whitened_chi2([points @ a.T + b - yb for a, b, yb in zip(self.A, self.b, y)], _models())

    def region(self, points, y):
        """The region in a box of +-8 half-widths around the truth (wide enough never to clip it)."""
        return region_extent(lambda x: self.chi2(x, y), self.truth - 8 * self.half, self.truth + 8 * self.half,
                             points, LEVEL)


def test_region_projections_equal_the_analytic_ellipsoid():
    """A sparse archive far from the minimum (20 points): the computed extent is sqrt(χ²_2(0.95) [(A'Σ⁻¹A)⁻¹]_ii)
    around the GLS estimate, and the minimum is the GLS minimum of the dense-covariance misfit."""
    lg, rng = _LinearGaussian(), np.random.default_rng(3)
    y = lg.data(rng)
    points = lg.truth + lg.half * rng.uniform(3.0, 6.0, (20, 2))  # none of them inside the region
    region = lg.region(points, y)
    centre, half = (region.upper + region.lower) / 2, (region.upper - region.lower) / 2
    np.testing.assert_allclose(half, lg.half, rtol=1e-3)
    np.testing.assert_allclose(centre, lg.gls(y), atol=1e-3 * lg.half.max())
    np.testing.assert_allclose(region.best, lg.gls(y), atol=1e-3 * lg.half.max())
    assert region.threshold == pytest.approx(lg.q)
    assert region.chi2_min == pytest.approx(lg.chi2_dense(lg.gls(y), y), rel=1e-6)
    assert region.count == 0


def test_region_is_clipped_by_the_box():
    lg, rng = _LinearGaussian(), np.random.default_rng(4)
    y = lg.data(rng)
    centre = lg.gls(y)
    lower, upper = centre - 0.5 * lg.half, centre + 4 * lg.half
    region = region_extent(lambda x: lg.chi2(x, y), lower, upper, lg.archive(rng, 10, 2.0), LEVEL)
    np.testing.assert_allclose(region.lower, lower)
    assert np.all(region.upper < upper) and np.all(region.upper > centre + 0.9 * lg.half)


def test_coverage_over_noise_draws_matches_the_level():
    """200 seeded noise draws: the joint region holds the truth with probability 0.95 (χ²_2 of the exact Δχ²), the
    per-parameter ranges hold it with the probability of the ellipsoid's bounding box, P(|Z_i| <= sqrt(q) for all i),
    Z ~ N(0, corr(C)), estimated here by Monte Carlo."""
    lg, rng = _LinearGaussian(), np.random.default_rng(5)
    points = lg.archive(rng, 30, 3.5)
    draws = 200
    joint = box = 0
    for _ in range(draws):
        y = lg.data(rng)
        region = lg.region(points, y)
        joint += lg.chi2_dense(lg.truth, y) - region.chi2_min <= region.threshold
        box += bool(np.all((region.lower <= lg.truth) & (lg.truth <= region.upper)))
    sd = np.sqrt(np.diag(lg.C))
    z = rng.multivariate_normal(np.zeros(2), lg.C / np.outer(sd, sd), size=1_000_000)
    p_box = np.mean(np.all(np.abs(z) <= np.sqrt(lg.q), axis=1))
    for count, p in ((joint, LEVEL), (box, p_box)):
        assert abs(count - draws * p) <= 3 * np.sqrt(draws * p * (1 - p)), (count, p)


def test_bad_levels_and_chi2_values_are_refused():
    for level in (0.0, 1.0, 1.5):
        with pytest.raises(ParameterError, match="confidence_level"):
            region_extent(lambda x: np.zeros(len(x)), np.zeros(2), np.ones(2), np.zeros((2, 2)), level)
        with pytest.raises(ParameterError, match="confidence_level"):
            NSGA2Calibration(confidence_level=level)
    with pytest.raises(ParameterError, match="finite chi2"):
        region_extent(lambda x: np.full(len(x), np.nan), np.zeros(2), np.ones(2), np.zeros((2, 2)), 0.9)


# --- the measurement model through the observations stage ----------------------------------------------------------

def test_observations_carry_the_measurement_model(tmp_path):
    kept = Observations(dead_volume="keep").run(CTX)
    corrected = Observations().run(CTX)  # effluent series moved back by the files' 2 ml outlet line
    for name, obs in itertools.product(("BCF1", "BCF2"), (kept, corrected)):
        ds = load_coreflood(name)
        if obs is corrected:  # the file with its effluent at the core outlet; no dead volume left in the model
            ds = at_core_outlet(ds, ds.attrs["noise_dead_volume_ml"] / ds.attrs["pore_volume_ml"])
        direct = load_experiments([ds], 0.1)[0]
        carried = observed_experiment(obs, name)
        expected = direct.measurement if obs is kept else replace(direct.measurement, dead_volume_ml=0.0)
        assert carried.measurement == expected and carried.noise_from_data
        assert carried.core == direct.core and carried.schedule == direct.schedule
        assert (carried.pore_volume_ml, carried.ooip_ml) == (direct.pore_volume_ml, direct.ooip_ml)
        np.testing.assert_array_equal(carried.pv, direct.pv)
        for variable, series in carried.observed.items():
            np.testing.assert_array_equal(series, direct.observed[variable])
    # a lab file without a measurement model: the default NoiseModel, flagged as assumed
    ds = load_coreflood("BCF1")
    ds.attrs = {k: v for k, v in ds.attrs.items() if not k.startswith("noise_")}
    ds.to_netcdf(tmp_path / "lab.nc")
    exp = observed_experiment(Observations(experiments=[str(tmp_path / "lab.nc")]).run(CTX), "BCF1")
    assert exp.measurement == NoiseModel() and not exp.noise_from_data


# --- the stage ------------------------------------------------------------------------------------------------------

def test_stage_reports_noise_consistent_ranges():
    space = ParameterSpace(names=list(TABLE_3_2), ranges=TABLE_3_2).run(CTX)
    surrogate, observations = _linear_problem(space, Observations().run(CTX), {"recovery": Z_A, "dp": Z_A},
                                              orthonormal=False)
    out = _small_run().run(CTX, surrogate=surrogate.to_dataset(), observations=observations, space=space)
    assert out.attrs["confidence_archive_size"] == 40 + 7 * 40
    assert out.attrs["confidence_level"] == 0.95
    assert out.attrs["confidence_threshold"] == pytest.approx(stats.chi2.ppf(0.95, df=9))
    assert out.attrs["confidence_noise_model"] == "from the data"
    assert out.attrs["confidence_blocks"] == "recovery/BCF1 dp/BCF1"
    n_data = sum(int(np.isfinite(observations[v].sel(experiment="BCF1")).sum()) for v in ("recovery", "dp"))
    assert out.attrs["confidence_n_data"] == n_data
    assert 0 <= int(out["confidence_count"]) <= 320
    lo, hi = out["confidence_lower"].values, out["confidence_upper"].values
    assert np.all(out["prior_lower"].values <= lo) and np.all(lo <= hi) and np.all(hi <= out["prior_upper"].values)
    # per-parameter units, the same convention as the calibrated ranges (docs/architecture.md, Units and CF metadata)
    assert out["confidence_lower"].attrs == out["calibrated_lower"].attrs
    best = out["confidence_best"].values
    assert np.all(lo <= best) and np.all(best <= hi)


def test_a_rejected_model_carries_a_warning():
    """The goodness-of-fit p-value of the minimum: with 11 data and 9 parameters (2 degrees of freedom) the χ²
    survival function is exp(-χ²/2); below 0.01 the ranges are flagged as conditional on a rejected model."""
    from types import SimpleNamespace

    from spflow.plugins.calibration.nsga2_confidence import ConfidenceRegion

    ds = xr.Dataset(coords={"param": [f"p{i}" for i in range(9)]})
    noise = SimpleNamespace(n_data=11, noise_from_data=True, pairs=[("dp", "BCF1")])
    for chi2_min, flagged in ((5.0, False), (12.0, True)):
        region = ConfidenceRegion(np.zeros(9), np.ones(9), 3, 0.95, 16.9, chi2_min, np.full(9, 0.5))
        out = NSGA2Calibration._add_confidence(ds, region, noise, 100)
        assert out.attrs["confidence_fit_pvalue"] == pytest.approx(np.exp(-chi2_min / 2), rel=1e-12)
        assert ("confidence_warning" in out.attrs) == flagged
