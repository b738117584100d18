"""The permeability generator: its statistics over several seeds against the stated covariance model (variance of
ln k, exponential variogram and its range), reproducibility, the sample-variogram helper against a brute-force
pair loop, and bad input."""

import numpy as np
import pytest

from spflow.plugins.forward.two_d import permeability_field, sample_variogram
from spflow.plugins.forward.two_d.permeability_field import log_permeability

SEEDS = range(12)
NX, NY = 160, 80
VAR = 0.1
LX, LY = 0.1, 0.1  # fractions of the domain


def _fields(length=1.0, width=0.5):
    return [np.log(permeability_field(NX, NY, mean_md=300.0, variance=VAR, correlation_length=(LX, LY),
                                      length=length, width=width, seed=s).values / 300.0) for s in SEEDS]


def _within(sample, expected, n_se=4.0):
    """Mean over seeds within ``n_se`` standard errors (from the seed-to-seed spread) of ``expected``."""
    sample = np.asarray(sample)
    se = sample.std(axis=0, ddof=1) / np.sqrt(sample.shape[0])
    return np.abs(sample.mean(axis=0) - expected) <= n_se * se


def test_variance_of_log_k():
    """E[mean(Y^2)] = sigma^2 exactly for the known zero mean (ln k_geo)."""
    ys = _fields()
    assert _within([np.mean(y * y) for y in ys], VAR)


@pytest.mark.parametrize("axis", [0, 1])
def test_variogram_matches_exponential_model_and_range(axis):
    length, width = 1.0, 0.5
    ys = _fields(length, width)
    spacing, corr = (width / NY, LY * width) if axis == 0 else (length / NX, LX * length)
    max_lag = 40
    h = np.arange(1, max_lag + 1) * spacing
    gammas = np.array([sample_variogram(y, axis, max_lag) for y in ys])
    expected = VAR * (1.0 - np.exp(-h / corr))
    assert np.all(_within(gammas, expected))
    # correlation length: where the mean variogram crosses sigma^2 (1 - 1/e), linearly interpolated
    mean = gammas.mean(axis=0)
    k = np.nonzero(mean >= VAR * (1.0 - np.exp(-1.0)))[0][0]
    h_cross = np.interp(VAR * (1.0 - np.exp(-1.0)), mean[k - 1:k + 1], h[k - 1:k + 1])
    assert h_cross == pytest.approx(corr, rel=0.15)


def test_reproducible_and_seed_dependent():
    a = permeability_field(40, 10, seed=5)
    b = permeability_field(40, 10, seed=5)
    c = permeability_field(40, 10, seed=6)
    assert np.array_equal(a.values, b.values)
    assert not np.allclose(a.values, c.values)
    assert a.dims == ("y", "x") and a.attrs["units"] == "mD" and np.all(a.values > 0.0)


def test_sample_variogram_against_pair_loop():
    rng = np.random.default_rng(0)
    y = rng.normal(size=(6, 9))
    for axis in (0, 1):
        got = sample_variogram(y, axis, 4)
        for h in range(1, 5):
            pairs = [(y[i, j] - (y[i + h, j] if axis == 0 else y[i, j + h])) ** 2
                     for i in range(y.shape[0] - (h if axis == 0 else 0))
                     for j in range(y.shape[1] - (h if axis == 1 else 0))]
            assert got[h - 1] == pytest.approx(0.5 * np.mean(pairs), rel=1e-14)


def test_log_permeability_zero_variance_is_zero():
    assert np.all(log_permeability(8, 4, dx=0.1, dy=0.1, variance=0.0, lx=0.1, ly=0.1, seed=0) == 0.0)


@pytest.mark.parametrize("kwargs,match", [({"variance": -0.1}, "variance"), ({"correlation_length": (0.1, 0.0)},
                                                                             r"correlation_length\[1\]"),
                                          ({"mean_md": 0.0}, "mean_md"), ({"length": float("nan")}, "length")])
def test_bad_generator_input(kwargs, match):
    with pytest.raises(ValueError, match=match):
        permeability_field(10, 5, **kwargs)


def test_bad_shape_and_variogram_input():
    with pytest.raises(ValueError, match="nx"):
        permeability_field(0, 5)
    with pytest.raises(ValueError, match="max_lag"):
        sample_variogram(np.zeros((4, 4)), 1, 4)
    with pytest.raises(ValueError, match="axis"):
        sample_variogram(np.zeros((4, 4)), 2, 1)
