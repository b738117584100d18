"""The scale of the numerical-error term estimated from calibration residuals (numerical_scale.py), against
references computed here: dense Gaussian covariances written from the AR(1) / random-walk definitions, and
residuals simulated with numpy as measurement noise plus a numerical-error component of known size."""

import numpy as np
import pytest
from scipy.stats import multivariate_normal

from spflow.core.errors import ParameterError
from spflow.plugins.gap.error_model import BlockErrorModel
from spflow.plugins.gap.layout import Block, Layout
from spflow.plugins.gap.numerical_scale import estimate_scale, scale_log_likelihood

TAU = 0.5


def _block(variable, scale, phi):
    n = scale.size
    return Block(variable, "X", np.arange(n), np.arange(n, dtype=float), np.zeros(n), np.zeros(n, int),
                 BlockErrorModel(np.asarray(scale, float), phi))


def _dense(scale, phi):
    """Covariance from the definitions: stationary AR(1) of scales c, Sigma_ij = c_i c_j phi^|i-j|; random walk
    (phi = 1), Sigma_ij = sum_{k <= min(i, j)} c_k^2."""
    n = scale.size
    i, j = np.meshgrid(np.arange(n), np.arange(n), indexing="ij")
    if phi == 1.0:
        return np.cumsum(scale**2)[np.minimum(i, j)]
    return np.outer(scale, scale) * phi ** np.abs(i - j)


def _bumps(n, centres, height, width):
    x = np.arange(n, dtype=float)
    return height * sum(np.exp(-0.5 * ((x - c) / width) ** 2) for c in centres)


@pytest.mark.parametrize("phi", [0.0, 0.6, 1.0])
def test_log_determinant_is_that_of_the_dense_covariance(phi):
    scale = np.linspace(0.5, 2.0, 7) ** 1.3
    expected = np.linalg.slogdet(_dense(scale, phi))[1]
    assert BlockErrorModel(scale, phi).log_determinant() == pytest.approx(expected, rel=1e-10)


def test_log_likelihood_is_the_gaussian_marginal_of_the_residuals():
    rng = np.random.default_rng(3)
    n = 9
    a = {"dp": rng.uniform(0.5, 2.0, n), "oil_cut": np.full(n, 0.3), "recovery": np.full(n, 0.2)}
    phi = {"dp": 0.7, "oil_cut": 0.0, "recovery": 1.0}
    layout = Layout(tuple(_block(v, a[v], phi[v]) for v in a))
    d = {("dp", "X"): rng.uniform(0.0, 3.0, n), ("recovery", "X"): np.cumsum(rng.uniform(0.0, 0.4, n))}
    jac = rng.standard_normal((3 * n, 3))
    r = rng.standard_normal(3 * n)
    for s in (0.0, 0.7, 1.9):
        # the numerical part: scales sqrt(a^2 + s^2 d^2); for the random walk, innovations from increments of d
        c = {"dp": np.sqrt(a["dp"] ** 2 + (s * d[("dp", "X")]) ** 2), "oil_cut": a["oil_cut"],
             "recovery": np.sqrt(a["recovery"] ** 2 + (s * np.abs(np.diff(d[("recovery", "X")], prepend=0.0))) ** 2)}
        sigma = np.zeros((3 * n, 3 * n))
        for k, v in enumerate(a):
            sigma[k * n:(k + 1) * n, k * n:(k + 1) * n] = _dense(c[v], phi[v])
        expected = multivariate_normal(np.zeros(3 * n), sigma + TAU**2 * jac @ jac.T).logpdf(r)
        assert scale_log_likelihood(layout, d, r, jac, TAU, s) == pytest.approx(expected, rel=1e-9)


def _study(s_true, seeds, n=240, p=4):
    """Estimates on residuals simulated as r = J delta + a e1 + s_true d e2 (white block) and a random walk with
    innovations a w1 + s_true |diff d| w2, then least-squares fitted (the calibrated base's residuals)."""
    a_white, a_walk = 1.0, 0.5
    d_white = _bumps(n, (40, 120, 200), 3.0, 6.0)
    d_walk = np.cumsum(_bumps(n, (60, 150), 1.0, 5.0))
    layout = Layout((_block("dp", np.full(n, a_white), 0.0), _block("recovery", np.full(n, a_walk), 1.0)))
    spread = {("dp", "X"): d_white, ("recovery", "X"): d_walk}
    out = []
    for seed in seeds:
        rng = np.random.default_rng(seed)
        jac = rng.standard_normal((2 * n, p)) * np.r_[np.full(n, a_white), np.full(n, a_walk)][:, None]
        white = a_white * rng.standard_normal(n) + s_true * d_white * rng.standard_normal(n)
        walk = np.cumsum(a_walk * rng.standard_normal(n)
                         + s_true * np.abs(np.diff(d_walk, prepend=0.0)) * rng.standard_normal(n))
        r = jac @ (TAU * rng.standard_normal(p)) + np.r_[white, walk]
        # the calibration: weighted least squares under the measurement error alone
        w0 = layout.whiten(r)
        j0 = layout.whiten(jac)
        r_fit = r - jac @ np.linalg.lstsq(j0, w0, rcond=None)[0]
        out.append(estimate_scale(layout, spread, r_fit, jac, TAU, maximum=2.0))
    return out


def test_recovers_the_true_scale_within_its_interval_over_seeds():
    est = _study(1.0, range(1000, 1200))
    values = np.array([e.estimate for e in est])
    covered = np.mean([e.lower <= 1.0 <= e.upper for e in est])
    assert covered >= 0.9                       # nominal 0.95; 200 seeds: binomial sd 0.015
    assert abs(np.mean(values) - 1.0) < 0.03    # sd of one estimate ~0.1 here, of the mean ~0.007
    assert all(e.profile.max() <= 1e-9 and e.lower <= e.estimate <= e.upper for e in est)


def test_pure_noise_gives_a_scale_near_zero():
    est = _study(0.0, range(100, 160))
    values = np.array([e.estimate for e in est])
    assert np.median(values) < 0.1
    assert np.mean([e.lower == 0.0 for e in est]) >= 0.9
    assert np.mean([e.upper for e in est]) < 0.6    # the data do rule out the worst case s = 1


def test_capped_at_the_maximum_and_bad_input_is_an_error():
    (big,) = _study(5.0, [7])
    assert big.estimate == pytest.approx(2.0) and big.upper == 2.0 and big.lower > 1.0
    layout = Layout((_block("dp", np.ones(5), 0.0),))
    with pytest.raises(ParameterError, match="numerical_scale_max"):
        estimate_scale(layout, {}, np.zeros(5), np.zeros((5, 1)), TAU, maximum=-1.0)
    with pytest.raises(ParameterError, match="finite residuals"):
        estimate_scale(layout, {}, np.full(5, np.nan), np.zeros((5, 1)), TAU)


def test_a_diagnosis_checks_the_cap_before_any_work():
    from spflow.plugins.gap.base_model import BaseModel
    from spflow.plugins.gap.diagnosis import Options, diagnose

    base = BaseModel.from_mapping({"cells": 12, "parameters": {"AP1": [5.0, 40.0]}})
    with pytest.raises(ParameterError, match=r"numerical_scale_max = -0.5 .*allowed \[0, 10\]"):
        diagnose(["no_such_file.nc"], [], base, options=Options(numerical_scale_max=-0.5))
