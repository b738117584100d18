"""The nsga2_calibration stage on test surrogates with known answers: objectives (Eq. 3.16), the Pareto set of a
problem whose Pareto set is known analytically, bad input, and cache reuse in a small pipeline."""

import numpy as np
import pytest
import xarray as xr

import spflow
from spflow.core.errors import ParameterError
from spflow.core.stage import Stage, StageContext
from spflow.plugins.calibration.nsga2_problem import SurrogateMisfitProblem
from spflow.plugins.calibration.nsga2_pareto_design import ParetoDesign
from spflow.plugins.calibration.nsga2_stage import NSGA2Calibration
from spflow.plugins.design.parameter_space import ParameterSpace
from spflow.plugins.design.schemas import DESIGN, SPACE
from spflow.plugins.forward.simulate import common_grid
from spflow.plugins.forward.stage import RESPONSES
from spflow.plugins.observations import Observations
from spflow.plugins.surrogates.contract import SURROGATE, Surrogate
from spflow.plugins.surrogates.outputs import OutputIndex, stack_outputs

from surrogate_kind_plugin import surrogate_kinds_registered

TABLE_3_2 = {"ALPHAV2": [0.0, 3.0], "HBNC70": [0.02, 0.05], "HBNC71": [0.01, 0.02], "AD31": [0.0, 2.0],
             "GAMHF": [55.0, 100.0], "CRK": [0.05, 0.1], "E2C": [1.5, 3.0], "E2WC": [1.5, 3.0],
             "ALPHAL1": [0.008, 0.012]}
CTX = StageContext("test", verbose=False)
#: Two points of the unit box [-1, 1]^9 used as known optima.
Z_A = np.array([-0.5, 0.4, 0.2, -0.3, 0.6, 0.0, -0.6, 0.3, 0.1])
Z_B = np.array([0.5, -0.2, 0.6, 0.3, -0.4, 0.5, 0.2, -0.5, -0.3])


class LinearSurrogate(Surrogate):
    """Exact affine model in the unit coordinates z = to_unit(x): mean = intercept + z @ slopes, zero variance."""

    kind = "nsga_test_linear"

    def __init__(self, names, lower, upper, outputs, intercept, slopes):
        super().__init__(names, lower, upper, outputs)
        self.intercept, self.slopes = np.asarray(intercept, float), np.asarray(slopes, float)

    def _predict(self, x):
        mean = self.intercept + self.to_unit(x) @ self.slopes
        return mean, np.zeros_like(mean)

    def to_dataset(self):
        return self._dataset({"intercept": ("output", self.intercept), "slopes": (("param", "output"), self.slopes)})

    @classmethod
    def from_dataset(cls, ds):
        return cls(**cls._common(ds), intercept=ds["intercept"].values, slopes=ds["slopes"].values)


@pytest.fixture(autouse=True, scope="module")
def toy_kind_registered():
    with surrogate_kinds_registered(LinearSurrogate, name="test_nsga_stage_kind"):
        yield


class LinearFit(Stage):
    """Least-squares affine surrogate of forward responses (a stand-in for the pce stage in the cache test)."""

    name = "nsga_test_linear_fit"
    inputs = {"space": SPACE, "design": DESIGN, "responses": RESPONSES}
    output = SURROGATE
    params = {"variables": spflow.Param(list, ["recovery", "dp"]), "experiments": spflow.Param(list, ["BCF1"])}

    def run(self, ctx, space, design, responses):
        y, index = stack_outputs(responses, self.params["variables"], self.params["experiments"])
        lower, upper = space["lower"].values, space["upper"].values
        z = 2 * (design["values"].values - lower) / (upper - lower) - 1
        coef = np.linalg.lstsq(np.c_[np.ones(len(z)), z], y, rcond=None)[0]
        return LinearSurrogate(list(space["param"].values), lower, upper, index, coef[0], coef[1:]).to_dataset()


@pytest.fixture(scope="module")
def space():
    return ParameterSpace(names=list(TABLE_3_2), ranges=TABLE_3_2).run(CTX)


@pytest.fixture(scope="module")
def bundled():
    return Observations().run(CTX)


def _bcf1_index(observations):
    """Output columns for recovery and dp of BCF1 on its simulator grid (0, 0.1, ..., 4.2, 4.23 PV), labelled as the
    forward stage labels them."""
    pv = common_grid([float(observations["total_pv"].sel(experiment="BCF1"))], 0.1)[0]
    variables = np.repeat(["recovery", "dp"], pv.size)
    return OutputIndex(variables, np.full(variables.size, "BCF1"), np.tile(pv, 2), {"recovery": "1", "dp": "Pa"})


def _surrogate(space, index, slopes, intercept):
    return LinearSurrogate(list(space["param"].values), space["lower"].values, space["upper"].values, index,
                           intercept, slopes)


def _unit(space, x):
    lo, hi = space["lower"].values, space["upper"].values
    return 2 * (x - lo) / (hi - lo) - 1


def _objectives_by_hand(space, observations, index, intercept, slopes, x):
    """½ Σ (P − y)² over the PV points where BCF1 has a finite observation, computed from the coefficients."""
    prediction = intercept + _unit(space, x) @ slopes
    out = []
    for variable in ("recovery", "dp"):
        cols = np.flatnonzero(index.variable == variable)
        obs = observations[variable].sel(experiment="BCF1").sel(pv=index.pv[cols], method="nearest").values
        keep = np.isfinite(obs)
        out.append(0.5 * np.sum((prediction[:, cols[keep]] - obs[keep]) ** 2, axis=1))
    return np.stack(out, axis=1)


def _small_run(**overrides):
    params = dict(population=40, generations=8, n_cross=4, cells=10, snapshots=[1, 4], seed=3)
    return NSGA2Calibration(**(params | overrides))


def test_objectives_are_half_squared_misfits_of_the_training_coreflood(space, bundled):
    rng = np.random.default_rng(0)
    index = _bcf1_index(bundled)
    intercept = np.where(index.variable == "dp", 2e4, 0.4) * (1 + 0.1 * rng.standard_normal(len(index)))
    slopes = np.where(index.variable == "dp", 3e3, 0.05) * rng.standard_normal((9, len(index)))
    surrogate = _surrogate(space, index, slopes, intercept)
    names, lo, hi = list(space["param"].values), space["lower"].values, space["upper"].values
    problem = SurrogateMisfitProblem(surrogate, bundled, names, lo, hi, ["recovery", "dp"], ["BCF1"])
    x = lo + (hi - lo) * rng.random((25, 9))
    expected = _objectives_by_hand(space, bundled, index, intercept, slopes, x)
    np.testing.assert_allclose(problem.objectives(x), expected, rtol=1e-12)

    # the surrogate stores its parameters in another order: the stage must permute the columns
    perm = rng.permutation(9)
    shuffled = LinearSurrogate([names[i] for i in perm], lo[perm], hi[perm], index, intercept, slopes[perm])
    problem = SurrogateMisfitProblem(shuffled, bundled, names, lo, hi, ["recovery", "dp"], ["BCF1"])
    np.testing.assert_allclose(problem.objectives(x), expected, rtol=1e-12)

    # and the stage's stored Pareto objectives are those of its stored designs
    out = _small_run().run(CTX, surrogate=surrogate.to_dataset(), observations=bundled, space=space)
    np.testing.assert_allclose(out["objectives"].values,
                               _objectives_by_hand(space, bundled, index, intercept, slopes, out["designs"].values),
                               rtol=1e-10)
    assert out["objective_unit"].values.tolist() == ["1", "(Pa)^2"]


def _linear_problem(space, bundled, targets, orthonormal):
    """A linear surrogate of BCF1's recovery and dp whose "observations" are its own predictions at ``targets``
    (variable -> unit coordinates z_s). With ``orthonormal`` slope rows, q_s = c_s ½‖z − z_s‖² exactly."""
    rng = np.random.default_rng(7)
    index = _bcf1_index(bundled)
    slopes, intercept = np.zeros((9, len(index))), np.zeros(len(index))
    observations = bundled.copy(deep=True)
    for variable, scale in (("recovery", 0.1), ("dp", 1e3)):
        cols = np.flatnonzero(index.variable == variable)
        rows = np.linalg.qr(rng.standard_normal((cols.size, 9)))[0].T if orthonormal else \
            rng.standard_normal((9, cols.size))
        slopes[:, cols] = scale * rows
        observations[variable].loc[dict(experiment="BCF1", pv=index.pv[cols])] = targets[variable] @ slopes[:, cols]
    return _surrogate(space, index, slopes, intercept), observations


def _conflicting(space, bundled):
    return _linear_problem(space, bundled, {"recovery": Z_A, "dp": Z_B}, orthonormal=True)


def test_pareto_set_approaches_a_known_common_optimum(space, bundled):
    """Data generated by the surrogate at one point ξ*: both objectives vanish there, so the Pareto set shrinks
    onto ξ*."""
    z_star = Z_A
    surrogate, observations = _linear_problem(space, bundled, {"recovery": z_star, "dp": z_star}, orthonormal=False)
    out = NSGA2Calibration(population=60, generations=80, n_cross=80, cells=10, snapshots=[1], seed=5).run(
        CTX, surrogate=surrogate.to_dataset(), observations=observations, space=space)
    z = _unit(space, out["designs"].values)
    assert np.abs(z - z_star).max() < 0.03  # every Pareto member within 1.5 % of each range from ξ*
    lo, hi = _unit(space, out["calibrated_lower"].values), _unit(space, out["calibrated_upper"].values)
    assert np.all(lo - 0.03 <= z_star) and np.all(z_star <= hi + 0.03)
    first = out["front_objectives"].sel(snapshot=1).min("member")
    assert np.all(out["objectives"].max("pareto") < 1e-3 * first)  # both misfits fell by more than 1000x
    hv = out["hypervolume"].values
    assert np.all(np.diff(hv) >= -1e-12) and hv[-1] > hv[0]  # elitism: the front never gets worse
    assert out["checkpoint"].values.tolist() == [80] and out.attrs["generations_run"] == 80


def test_pareto_front_of_conflicting_objectives_reaches_the_analytic_front(space, bundled):
    """Recovery and dp generated at different points z_1, z_2 with isotropic misfits: the Pareto set is the segment
    [z_1, z_2], where ‖z − z_1‖ + ‖z − z_2‖ = ‖z_1 − z_2‖ (triangle inequality; larger anywhere else)."""
    za, zb = Z_A, Z_B
    surrogate, observations = _conflicting(space, bundled)
    out = NSGA2Calibration(n_cross=100, cells=10, snapshots=[1], seed=1).run(  # thesis settings: 120 x 100
        CTX, surrogate=surrogate.to_dataset(), observations=observations, space=space)
    z = _unit(space, out["designs"].values)
    # the objectives are exactly the isotropic quadratics
    np.testing.assert_allclose(out["objectives"].values,
                               np.c_[0.5 * 0.1**2 * np.sum((z - za) ** 2, axis=1),
                                     0.5 * 1e3**2 * np.sum((z - zb) ** 2, axis=1)], rtol=1e-8)
    length = np.linalg.norm(zb - za)
    excess = (np.linalg.norm(z - za, axis=1) + np.linalg.norm(z - zb, axis=1) - length) / length
    assert excess.max() < 0.06 and np.median(excess) < 0.02, (excess.max(), np.median(excess))
    t = (z - za) @ (zb - za) / length**2  # position along the segment
    assert t.min() < 0.15 and t.max() > 0.85  # the front spans the trade-off from one optimum to the other


def test_history_snapshots_and_checkpoints_follow_algorithm_3(space, bundled):
    surrogate, observations = _conflicting(space, bundled)
    out = _small_run().run(CTX, surrogate=surrogate.to_dataset(), observations=observations, space=space)
    assert out["generation"].values.tolist() == list(range(1, 9))
    assert out["snapshot"].values.tolist() == [1, 4, 8]  # requested ones plus the last generation
    assert out["checkpoint"].values.tolist() == [4, 8]  # every n_cross generations and the last
    assert int(out["front_size"].sel(snapshot=8)) == out.sizes["pareto"] == int(out["n_front"][-1])
    # the final front snapshot is the Pareto set (stored sorted by the first objective)
    final = out["front_objectives"].sel(snapshot=8).dropna("member")
    np.testing.assert_allclose(np.sort(final.values[:, 0]), out["objectives"].values[:, 0])
    # sigma_loss is the mean of the held-out misfits (here of the observations' own BCF2/BCF3 data)
    assert float(out["sigma_loss"].sel(checkpoint=8)) == pytest.approx(float(out["heldout_misfit"].mean()))


def test_heldout_misfit_over_the_consistent_pareto_points(space, bundled):
    """Each Pareto point's training χ² is at least the region's minimum; the flags follow the likelihood-ratio
    threshold against the region's minimum and against the front's best point, and sigma_loss_consistent averages
    the held-out misfits of the front-consistent points only."""
    surrogate, observations = _conflicting(space, bundled)
    out = _small_run().run(CTX, surrogate=surrogate.to_dataset(), observations=observations, space=space)
    chi2, chi2_min, limit = out["pareto_chi2"].values, out.attrs["confidence_chi2_min"], out.attrs["confidence_threshold"]
    assert np.all(chi2 >= chi2_min * (1 - 1e-9))
    np.testing.assert_array_equal(out["pareto_noise_consistent"].values, chi2 - chi2_min <= limit)
    kept = chi2 - chi2.min() <= limit
    np.testing.assert_array_equal(out["pareto_front_consistent"].values, kept)
    assert 1 <= out.attrs["heldout_consistent_count"] == int(kept.sum())
    per_point = out["heldout_misfit"].values.reshape(out.sizes["pareto"], -1)
    assert out.attrs["sigma_loss_consistent"] == pytest.approx(per_point[kept].mean())
    assert ("front_outside_region_warning" in out.attrs) == (not out["pareto_noise_consistent"].values.any())


def test_run_stops_at_the_first_checkpoint_where_sigma_loss_is_below_tolerance(space, bundled):
    surrogate, observations = _conflicting(space, bundled)
    full = _small_run().run(CTX, surrogate=surrogate.to_dataset(), observations=observations, space=space)
    sigma_4 = float(full["sigma_loss"].sel(checkpoint=4))
    stopped = _small_run(sigma_tol=sigma_4 * 1.0001).run(CTX, surrogate=surrogate.to_dataset(),
                                                           observations=observations, space=space)
    assert stopped.attrs["generations_run"] == 4 and "sigma_tol" in stopped.attrs["stop_reason"]
    assert stopped["checkpoint"].values.tolist() == [4] and stopped["snapshot"].values.tolist() == [1, 4]
    # same seed, so the same first four generations; a tolerance just below sigma_loss does not stop the run
    np.testing.assert_array_equal(stopped["hypervolume"].values, full["hypervolume"].values[:4])
    rerun = _small_run(sigma_tol=sigma_4 * 0.9999).run(CTX, surrogate=surrogate.to_dataset(),
                                                        observations=observations, space=space)
    assert rerun.attrs["generations_run"] == 8


def test_pareto_design_collects_the_stored_fronts(space, bundled):
    surrogate, observations = _conflicting(space, bundled)
    cal = _small_run().run(CTX, surrogate=surrogate.to_dataset(), observations=observations, space=space)
    design = ParetoDesign(generations=[1, 0]).run(CTX, calibration=cal)  # 0 = the last generation (8)
    for g in (1, 8):
        front = cal["front_designs"].sel(snapshot=g).dropna("member", how="all").values
        np.testing.assert_array_equal(design["values"].values[design["generation"].values == g], front)
    assert design.sizes["sample"] == int(cal["front_size"].sel(snapshot=[1, 8]).sum())
    with pytest.raises(ParameterError, match="stored generations"):
        ParetoDesign(generations=[5]).run(CTX, calibration=cal)


def _stored_fronts(fronts: dict[int, list[list[float]]]) -> xr.Dataset:
    """A calibration Dataset holding only what pareto_design reads: fronts NaN-padded to one member length."""
    width = max(len(f) for f in fronts.values())
    padded = [f + [[np.nan, np.nan]] * (width - len(f)) for f in fronts.values()]
    return xr.Dataset({"front_designs": (("snapshot", "member", "param"), np.array(padded, dtype=float)),
                       "front_size": ("snapshot", np.array([len(f) for f in fronts.values()])),
                       "param_unit": ("param", ["1", "1"])},
                      coords={"snapshot": list(fronts), "param": ["a", "b"]})


def test_pareto_design_drops_padding_and_refuses_a_nan_member():
    cal = _stored_fronts({1: [[0.1, 0.2]], 4: [[0.3, 0.4], [0.5, 0.6], [0.7, 0.8]]})
    design = ParetoDesign(generations=[1, 4]).run(CTX, calibration=cal)
    np.testing.assert_array_equal(design["values"].values, [[0.1, 0.2], [0.3, 0.4], [0.5, 0.6], [0.7, 0.8]])
    np.testing.assert_array_equal(design["generation"].values, [1, 4, 4, 4])
    broken = _stored_fronts({1: [[0.1, 0.2]], 4: [[0.3, 0.4], [0.5, np.nan], [0.7, 0.8]]})
    ParetoDesign(generations=[1]).run(CTX, calibration=broken)  # snapshot 1 is intact
    with pytest.raises(ParameterError, match=r"snapshot 4, member 1 is not finite in \['b'\]"):
        ParetoDesign(generations=[0]).run(CTX, calibration=broken)


def test_heldout_misfit_is_the_relative_l2_error_of_the_simulator(space, bundled):
    """The held-out misfit of each Pareto point equals ‖sim − obs‖/‖obs‖ recomputed from a direct simulate() call."""
    surrogate, observations = _conflicting(space, bundled)
    out = _small_run(generations=2, n_cross=2, population=8).run(
        CTX, surrogate=surrogate.to_dataset(), observations=observations, space=space)
    x = dict(zip(out["param"].values, out["designs"].values[0]))
    for experiment in ("BCF2", "BCF3"):
        sim = spflow.simulate(experiment, x, cells=10, pv_step=0.1)
        for variable in ("recovery", "dp"):
            obs = observations[variable].sel(experiment=experiment).dropna("pv")
            # pair each simulated PV with the finite observation at the same PV (to round-off)
            match = np.abs(sim["pv"].values[:, None] - obs["pv"].values[None, :]) < 1e-9
            s, o = sim[variable].values[match.any(axis=1)], obs.values[match.argmax(axis=1)[match.any(axis=1)]]
            expected = np.linalg.norm(s - o) / np.linalg.norm(o)
            got = float(out["heldout_misfit"].isel(pareto=0).sel(experiment=experiment, objective=variable))
            assert got == pytest.approx(expected, rel=1e-9)


def test_bad_input_is_named_before_any_work(space, bundled):
    with pytest.raises(ParameterError, match="training"):
        NSGA2Calibration(training="BCF2")
    with pytest.raises(ParameterError, match="variables"):
        NSGA2Calibration(variables=["dp", "dp"])
    with pytest.raises(ParameterError, match="crossover_prob"):
        NSGA2Calibration(crossover_prob=1.5)
    with pytest.raises(ParameterError, match="effect"):
        NSGA2Calibration(effects={"no_such_effect": 1.0})
    index = _bcf1_index(bundled)
    narrow = space.copy(deep=True)
    narrow["upper"].loc[dict(param="AD31")] = 1.0  # the surrogate only knows AD31 in [0, 1]
    surrogate = _surrogate(narrow, index, np.zeros((9, len(index))), np.zeros(len(index)))
    with pytest.raises(ParameterError, match="AD31"):
        _small_run().run(CTX, surrogate=surrogate.to_dataset(), observations=bundled, space=space)
    missing = bundled.sel(experiment=["BCF1", "BCF2"])
    surrogate = _surrogate(space, index, np.zeros((9, len(index))), np.zeros(len(index)))
    with pytest.raises(ParameterError, match="BCF3"):
        _small_run().run(CTX, surrogate=surrogate.to_dataset(), observations=missing, space=space)


class _Plugin:
    @spflow.hookimpl
    def spflow_register_stages(self, register):
        register(LinearFit)


def test_rerun_after_changing_only_generations_reuses_every_upstream_node(tmp_path):
    spflow.register_plugin(_Plugin(), name="nsga_test_plugin")
    try:
        p = spflow.Pipeline("nsga_cache")
        p.add("space", "parameter_space", params={"names": list(TABLE_3_2), "ranges": TABLE_3_2})
        p.add("design", "lhs_design", inputs={"space": "space"}, params={"samples": 24, "seed": 1})
        p.add("responses", "forward", inputs={"design": "design"}, params={"experiments": ["BCF1"], "cells": 10})
        p.add("surrogate", "nsga_test_linear_fit", inputs={"space": "space", "design": "design",
                                                            "responses": "responses"})
        p.add("observations", "observations")
        p.add("calibration", "nsga2_calibration",
              inputs={"surrogate": "surrogate", "observations": "observations", "space": "space"},
              params={"population": 12, "generations": 3, "n_cross": 3, "cells": 10, "snapshots": [1]})
        p.add("pareto_sets", "pareto_design", inputs={"calibration": "calibration"}, params={"generations": [1, 0]})
        first = spflow.run(p, cache=tmp_path)
        assert sorted(first.executed) == sorted(p.nodes)
        p.set_params("calibration", generations=5)
        second = spflow.run(p, cache=tmp_path)
        assert second.executed == ["calibration", "pareto_sets"]
        assert sorted(second.cached) == sorted(set(p.nodes) - {"calibration", "pareto_sets"})
        assert second["calibration"].attrs["generations_run"] == 5
        assert first["calibration"].attrs["generations_run"] == 3
    finally:
        spflow.unregister_plugin("nsga_test_plugin")


def test_each_generation_is_reported_as_progress(space, bundled):
    reports = []
    ctx = StageContext("nsga", verbose=False, report=lambda *report: reports.append(report))
    surrogate, observations = _conflicting(space, bundled)
    _small_run().run(ctx, surrogate=surrogate.to_dataset(), observations=observations, space=space)
    mine = [r for r in reports if r[3] == "generations"]
    assert mine[-1] == ("nsga", 8, 8, "generations")  # the last generation always goes through
    assert [r[1] for r in mine] == sorted(r[1] for r in mine) and set(r[1] for r in mine) <= set(range(1, 9))


def test_marginals_cut_inside_the_box_are_refused_and_laws_on_it_are_recorded(space, bundled, capsys):
    """The search runs on the space's box; a marginal whose support is narrower than its range (today's stage searched
    the whole box regardless) is refused before any work, and the laws of a space on its box are recorded."""
    from spflow.plugins.surrogates.input_marginals import (Beta, TruncatedNormal, Uniform, marginal_variables,
                                                           marginals_from_dataset)

    index = _bcf1_index(bundled)
    surrogate = _surrogate(space, index, np.zeros((9, len(index))), np.zeros(len(index))).to_dataset()
    names, lo, hi = list(space["param"].values), space["lower"].values, space["upper"].values
    laws = [Uniform(a, b) for a, b in zip(lo, hi)]
    laws[names.index("AD31")] = Beta(2.0, 3.0, 0.0, 1.0)  # AD31's range is [0, 2]: a beta on half of it
    with pytest.raises(ParameterError, match="nsga2_calibration.*'AD31'.*Beta.*not the space's range \\[0, 2\\]"):
        _small_run().run(CTX, surrogate=surrogate, observations=bundled, space=space.assign(marginal_variables(laws)))
    laws[names.index("AD31")] = TruncatedNormal(1.2, 0.3, 0.0, 2.0)  # on the range: accepted, searched on the box
    laws[names.index("E2C")] = Beta(2.0, 5.0, 1.5, 3.0)
    out = _small_run().run(StageContext("hm", verbose=True), surrogate=surrogate, observations=bundled,
                           space=space.assign(marginal_variables(laws)))
    assert marginals_from_dataset(out, "calibration") == laws
    assert "AD31 ~ TruncatedNormal(mean=1.2, std=0.3, lower=0, upper=2)" in out.attrs["marginals"].splitlines()
    assert out.attrs["search_space"].startswith("the space's box [lower, upper], searched uniformly")
    assert "[hm] searching the box uniformly; the space's laws:" in capsys.readouterr().err
    x = out["designs"].values
    assert np.all((x >= lo) & (x <= hi))
    box = _small_run().run(CTX, surrogate=surrogate, observations=bundled, space=space)
    assert "uniform on the ranges" in box.attrs["marginals"] and "distribution" not in box
    np.testing.assert_array_equal(box["designs"].values, x)  # the same search: the laws do not weight it
