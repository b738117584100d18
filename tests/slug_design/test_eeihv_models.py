"""Objective GPs and the EEIHV of designs: gradients through the GP against finite differences, posterior draws
against the predictive moments, the Kriging-believer conditioning, Pareto helpers against brute force, TMDSM."""

import moocore
import numpy as np
import pytest

from spflow.core.errors import ParameterError
from spflow.plugins.slug_design.bgo_loop import design_eeihv
from spflow.plugins.slug_design.knee import knee_point
from spflow.plugins.slug_design.objective_models import ObjectiveGP
from spflow.plugins.slug_design.pareto_front import hypervolume, nondominated, reference_point

BOUNDS = np.array([[0.0, 2.0], [-1.0, 1.0]])


def objectives(x):
    return np.column_stack([x[:, 0] + 0.3 * np.sin(3 * x[:, 1]), 2.0 - np.sqrt(x[:, 0] + 0.1) + x[:, 1] ** 2])


@pytest.fixture(scope="module")
def fitted():
    rng = np.random.default_rng(0)
    x = BOUNDS[:, 0] + rng.random((25, 2)) * np.ptp(BOUNDS, axis=1)
    y = objectives(x) + 0.02 * rng.standard_normal((25, 2))
    return x, y, tuple(ObjectiveGP.fit(x, y[:, k], BOUNDS, restarts=2, seed=k) for k in range(2))


def test_mean_and_std_gradients_equal_finite_differences(fitted):
    _, _, models = fitted
    x = np.array([[0.3, 0.2], [1.7, -0.8], [1.0, 0.5]])
    h = 1e-5  # the std carries round-off ~1e-12 of the kernel variance: keep it well below h·|∂s/∂x|
    for model in models:
        _, _, dmean, dstd = model.predict_with_gradient(x)
        for j in range(2):
            step = np.zeros(2)
            step[j] = h
            (mp, sp), (mm, sm) = model.predict(x + step), model.predict(x - step)
            np.testing.assert_allclose(dmean[:, j], (mp - mm) / (2 * h), rtol=1e-4, atol=1e-7)
            np.testing.assert_allclose(dstd[:, j], (sp - sm) / (2 * h), rtol=1e-4, atol=1e-6)


def test_design_eeihv_gradient_equals_finite_differences(fitted):
    x_obs, _, models = fitted
    means = np.column_stack([m.predict(x_obs)[0] for m in models])
    front = means[nondominated(means)]
    reference = reference_point(means)
    x = np.array([[0.2, 0.1], [1.5, -0.3], [0.9, 0.9], [0.05, -0.05]])
    value, grad = design_eeihv(models, x, front, reference)
    assert (value > 0).all()
    h = 1e-6
    for j in range(2):
        step = np.zeros(2)
        step[j] = h
        fd = (design_eeihv(models, x + step, front, reference)[0]
              - design_eeihv(models, x - step, front, reference)[0]) / (2 * h)
        np.testing.assert_allclose(grad[:, j], fd, rtol=1e-4, atol=1e-9)


def test_learned_noise_and_fit_quality():
    rng = np.random.default_rng(2)
    x = BOUNDS[:, 0] + rng.random((120, 2)) * np.ptp(BOUNDS, axis=1)
    y = objectives(x)[:, 0] + 0.1 * rng.standard_normal(120)
    model = ObjectiveGP.fit(x, y, BOUNDS, restarts=2)
    assert 0.1**2 / 2 < model.noise_variance < 0.1**2 * 2  # the noise is learned, not interpolated
    test = BOUNDS[:, 0] + rng.random((200, 2)) * np.ptp(BOUNDS, axis=1)
    mean, std = model.predict(test)
    error = mean - objectives(test)[:, 0]
    assert np.sqrt(np.mean(error**2)) < 0.05  # the mean filters the noise: error well below σ_n = 0.1
    assert np.mean(np.abs(error) < 2 * std) > 0.85  # and the latent std covers it


def test_posterior_draws_match_the_predictive_moments(fitted):
    _, _, models = fitted
    x = np.array([[0.3, 0.2], [0.35, 0.25], [1.9, -0.9]])
    draws = models[1].posterior_draws(x, 20000, np.random.default_rng(4))
    mean, std = models[1].predict(x)
    np.testing.assert_allclose(draws.mean(axis=0), mean, atol=4 * std.max() / np.sqrt(20000) * 1.5)
    np.testing.assert_allclose(draws.std(axis=0), std, rtol=0.03)
    assert np.corrcoef(draws[:, 0], draws[:, 1])[0, 1] > 0.5  # nearby designs are jointly drawn


def test_conditioning_keeps_hyperparameters_and_shrinks_variance(fitted):
    _, _, models = fitted
    model = models[0]
    x = np.array([[1.2, 0.4]])
    mean, std = model.predict(x)
    believer = model.conditioned_on(x, mean)
    new_mean, new_std = believer.predict(x)
    assert believer.hyperparameters()["noise_variance"] == pytest.approx(model.noise_variance)
    np.testing.assert_allclose(believer.hyperparameters()["lengthscale"], model.hyperparameters()["lengthscale"])
    assert new_mean[0] == pytest.approx(mean[0], abs=1e-6 * max(1.0, abs(mean[0])))
    assert new_std[0] < 0.02 * std[0]  # a latent (jitter-only) fantasy; with noise σ_n it would stay ~0.9 std
    elsewhere = np.array([[0.2, -0.7], [1.9, 0.9]])
    np.testing.assert_allclose(believer.predict(elsewhere)[0], model.predict(elsewhere)[0], rtol=1e-6, atol=1e-9)


def test_nondominated_and_hypervolume_against_brute_force():
    rng = np.random.default_rng(6)
    values = rng.random((60, 2))
    dominated = [any((values[j] <= values[i]).all() and (values[j] < values[i]).any() for j in range(60))
                 for i in range(60)]
    index = nondominated(values)
    assert sorted(index.tolist()) == [i for i in range(60) if not dominated[i]]
    assert (np.diff(values[index, 0]) > 0).all()
    reference = np.array([1.1, 1.2])
    # brute force: area of the union of boxes [p, r] on a fine grid of cell centres
    g1, g2 = np.meshgrid(np.linspace(0, 1.1, 1101)[:-1] + 0.0005, np.linspace(0, 1.2, 1201)[:-1] + 0.0005)
    covered = np.zeros(g1.shape, dtype=bool)
    for p in values[index]:
        covered |= (g1 >= p[0]) & (g2 >= p[1])
    assert hypervolume(values, reference) == pytest.approx(covered.mean() * 1.1 * 1.2, abs=3e-3)
    assert hypervolume(values, reference) == pytest.approx(moocore.hypervolume(values[index], ref=reference))


def test_reference_point_rule():
    values = np.array([[0.0, 5.0], [2.0, 1.0], [1.0, 3.0]])
    np.testing.assert_allclose(reference_point(values, 0.1), [2.2, 5.4])
    np.testing.assert_allclose(reference_point(values, 0.1, previous=np.array([3.0, 0.0])), [3.0, 5.4])


def test_knee_point_tmdsm():
    theta = np.linspace(0, np.pi / 2, 91)  # quarter circle bulging towards the utopia point (0, 0)
    front = np.column_stack([1 - np.sin(theta), 1 - np.cos(theta)])
    assert theta[knee_point(front)] == pytest.approx(np.pi / 4)
    scaled = front * np.array([1e6, 1e-3]) + np.array([-5e6, 7.0])  # units must not matter
    assert theta[knee_point(scaled)] == pytest.approx(np.pi / 4)
    with pytest.raises(ParameterError, match="knee_point: front"):
        knee_point(np.zeros((0, 2)))
