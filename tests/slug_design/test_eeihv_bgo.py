"""run_bgo end to end on a cheap noisy problem (noisy ZDT1, d = 2, whose noise-free front is known), batch mode,
the stopping rule, the result Dataset, front uncertainty, and bad inputs."""

import moocore
import numpy as np
import pytest

from spflow.core.errors import ParameterError
from spflow.plugins.slug_design.bgo_loop import run_bgo
from spflow.plugins.slug_design.front_uncertainty import front_uncertainty

BOUNDS = np.array([[0.0, 1.0], [0.0, 1.0]])
REFERENCE = np.array([1.1, 1.1])


def zdt1(x):
    """ZDT1 (Zitzler, Deb & Thiele 2000): front f2 = 1 − √f1 at x2 = 0."""
    g = 1.0 + 9.0 * x[:, 1]
    return np.column_stack([x[:, 0], g * (1.0 - np.sqrt(x[:, 0] / g))])


def noisy_zdt1(seed, sigma=0.05):
    rng = np.random.default_rng(seed)
    return lambda x: zdt1(x) + sigma * rng.standard_normal((x.shape[0], 2))


FAST = dict(gp_restarts=1, n_candidates=300, n_polish=2)


@pytest.fixture(scope="module")
def run():
    return run_bgo(noisy_zdt1(1), BOUNDS, n_init=8, max_iter=10, min_iter=10, seed=3, reference=REFERENCE, **FAST)


def test_bgo_improves_the_projected_front_over_the_initial_design(run):
    initial = moocore.hypervolume(zdt1(run.X[run.iteration == 0]), ref=REFERENCE)  # noise-free, all 8 designs
    final = moocore.hypervolume(zdt1(run.X[run.front_index]), ref=REFERENCE)  # noise-free, projected-front designs
    exact = 1.1 * 1.1 - 1.0 / 3.0  # area of the box minus the area under 1 − √f1
    assert final > initial + 0.15, (initial, final)
    assert final > 0.85 * exact, (final, exact)


def test_result_bookkeeping_and_dataset(run):
    assert run.X.shape == (18, 2) and run.Y.shape == (18, 2)
    np.testing.assert_array_equal(run.iteration, [0] * 8 + list(range(1, 11)))
    assert run.eeihv_max.shape == (10,) and (run.eeihv_max > 0).all()
    assert run.stop_reason == "max_iter"
    assert ((run.X >= 0) & (run.X <= 1)).all()
    # the projected front is non-dominated among the projected values (brute force)
    p = run.projected
    for i in run.front_index:
        assert not any((p[j] <= p[i]).all() and (p[j] < p[i]).any() for j in range(len(p)))
    ds = run.to_dataset(["x1", "x2"], ["1", "1"], ["f1", "f2"], ["1", "1"])
    assert dict(ds.sizes) == {"evaluation": 18, "design_var": 2, "objective": 2, "iteration": 10}
    # every numeric variable has units, or names the variable holding its units per element (docs/architecture.md)
    for v in ds.data_vars:
        if ds[v].dtype.kind in "fiu":
            attrs = ds[v].attrs
            assert "units" in attrs or attrs.get("units_variable") in ds.variables, v
    assert ds["on_front"].sum() == run.front_index.size
    np.testing.assert_array_equal(ds["reference"], REFERENCE)


def test_front_uncertainty(run):
    fu = front_uncertainty(run, n_fronts=30, n_designs=300, seed=0)
    assert np.unique(fu.sets).size == 30
    for j in range(30):  # each sampled front is non-dominated (brute force)
        f = fu.points[fu.sets == j]
        assert not any(((f <= a).all(axis=1) & (f < a).any(axis=1)).any() for a in f)
    mean_hv = np.mean([moocore.hypervolume(fu.points[fu.sets == j], ref=REFERENCE) for j in range(30)])
    # Vorob'ev: β* is chosen so that the expectation's hypervolume matches the mean hypervolume of the fronts
    assert fu.vorob_hypervolume == pytest.approx(mean_hv, rel=0.05)
    assert 0 < fu.vorob_threshold <= 100 and fu.vorob_deviation > 0
    surface = fu.attainment_surface(100 * 15 / 30)
    assert surface.shape[1] == 2 and surface.shape[0] >= 1


def test_batch_mode_and_stopping_rule():
    calls = []
    result = run_bgo(noisy_zdt1(2), BOUNDS, n_init=6, max_iter=5, min_iter=2, rtol=2.0, batch=3, seed=0,
                     callback=lambda r: calls.append(r.X.shape[0]), **FAST)
    # rtol = 2 > rel = 1 always: the run stops as soon as min_iter = 2 iterations are done
    assert result.stop_reason == "rtol"
    assert result.X.shape == (6 + 2 * 3, 2)
    np.testing.assert_array_equal(result.iteration, [0] * 6 + [1] * 3 + [2] * 3)
    assert result.eeihv_max.size == 3
    for it in (1, 2):  # the Kriging believer spreads a batch over distinct designs
        batch = result.X[result.iteration == it]
        assert min(np.linalg.norm(batch[a] - batch[b]) for a in range(3) for b in range(a)) > 1e-3
    assert calls == [6, 9, 12, 12]


@pytest.mark.parametrize("kwargs, field", [
    (dict(bounds=np.array([0.0, 1.0])), "bounds"),
    (dict(bounds=np.array([[0.0, 1.0], [1.0, 1.0]])), "bounds"),
    (dict(n_init=1), "n_init"),
    (dict(batch=0), "batch"),
    (dict(rtol=-1.0), "rtol"),
    (dict(reference=[1.0]), "reference"),
    (dict(kernel="cubic"), "kernel"),
])
def test_bad_inputs_raise_before_any_evaluation(kwargs, field):
    calls = []
    arguments = dict(objective=lambda x: calls.append(x) or zdt1(x), bounds=BOUNDS) | kwargs
    with pytest.raises(ParameterError, match=field):
        run_bgo(**arguments)
    assert calls == []


def test_non_finite_objective_values_are_named():
    def broken(x):
        y = zdt1(x)
        y[1, 0] = np.nan
        return y
    with pytest.raises(ParameterError, match=r"non-finite values \(Y\) at design rows \[1\]"):
        run_bgo(broken, BOUNDS, n_init=4)
    with pytest.raises(ParameterError, match=r"objective must return shape \(4, 2\)"):
        run_bgo(lambda x: zdt1(x)[:, :1], BOUNDS, n_init=4)
