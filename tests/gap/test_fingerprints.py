"""Projected fingerprints: the exact projector is the Frisch-Waugh-Lovell regression (score = t statistic of the
effect's coefficient), the regularised projector is (I + tau^2 J J')^-1, angles and absorption behave."""

import numpy as np
import pytest

from spflow.plugins.gap.fingerprints import NuisanceProjector, screen


def test_exact_projection_gives_the_regression_t_statistic():
    rng = np.random.default_rng(0)
    n, p = 80, 4
    J = rng.normal(size=(n, p))
    g = rng.normal(size=n) + J @ rng.normal(size=p)
    d = J @ rng.normal(size=p) + 0.7 * g + rng.normal(size=n)
    proj = NuisanceProjector(J, tau=np.inf)
    np.testing.assert_allclose(J.T @ proj.apply(g), 0.0, atol=1e-9)
    # regression d ~ [J, g] with unit noise: t = beta_g / sqrt(((X'X)^-1)_gg)
    X = np.column_stack([J, g])
    beta = np.linalg.lstsq(X, d, rcond=None)[0]
    t = beta[-1] / np.sqrt(np.linalg.inv(X.T @ X)[-1, -1])
    result = screen(["e"], [(1.0,)], [g[:, None]], d, proj)
    assert result.z[0][0] == pytest.approx(t, rel=1e-9)


def test_regularised_projector_is_the_woodbury_inverse():
    rng = np.random.default_rng(1)
    J = rng.normal(size=(30, 3))
    x = rng.normal(size=30)
    tau = 0.4
    explicit = np.linalg.inv(np.eye(30) + tau**2 * J @ J.T)
    proj = NuisanceProjector(J, tau)
    np.testing.assert_allclose(proj.apply(x), explicit @ x, rtol=1e-10)
    assert proj.norm(x) == pytest.approx(np.sqrt(x @ explicit @ x))


def test_angles_absorption_and_signs():
    rng = np.random.default_rng(2)
    J = rng.normal(size=(50, 2))
    a = rng.normal(size=50)
    b = rng.normal(size=50)
    proj = NuisanceProjector(J, tau=np.inf)
    fps = [np.column_stack([0.5 * a, a]), np.column_stack([2 * a]), np.column_stack([-b]), J[:, :1]]
    result = screen(["a", "a2", "b", "j"], [(1, 2), (3,), (1,), (1,)], fps, proj.apply(a), proj)
    assert result.cos[0, 1] == pytest.approx(1.0)
    np.testing.assert_allclose(result.cos, result.cos.T)
    assert result.z[0][0] == pytest.approx(result.z[0][1]) and result.z[0][0] > 0
    assert result.absorbed(3) == pytest.approx(1.0, abs=1e-6)  # a calibration direction: nothing left
    assert result.absorbed(0) < 0.2
    # the data residual is the projected fingerprint a: its score is its projected norm
    assert result.z[0][0] == pytest.approx(proj.norm(a))
