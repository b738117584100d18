"""Statistics of the measurement noise against the AR(1) / uniform formulas, on cheap synthetic signals.

Expected values and their sampling errors are derived here from the definitions (not from the code under test):
for a stationary AR(1) sequence with standard deviation s and lag-1 correlation r, the sample mean of N values
has standard error s sqrt((1 + r) / ((1 - r) N)), the sample variance s^2 sqrt(2 (1 + r^2) / ((1 - r^2) N)),
and the lag-k sample autocorrelation is r^k with standard error about sqrt((1 - r^2) / N) at lag 1.
"""

import math

import numpy as np
import pytest

from spflow.synthetic import NoiseModel
from spflow.synthetic.fraction_collector import read_oil_volumes
from spflow.synthetic.transducer import read_pressure

N = 200_000


def _autocorr(x, lag):
    d = x - x.mean()
    return float(np.dot(d[:-lag], d[lag:]) / np.dot(d, d))


@pytest.mark.parametrize("sigma, rho", [(0.05, 0.7), (0.02, 0.0), (0.03, 0.95)])
def test_pressure_noise_is_ar1_with_specified_mean_variance_and_correlation(sigma, rho):
    dp0, offset, drift, interval = 1.0e4, 300.0, 20.0, 0.01
    noise = NoiseModel(pressure_relative=sigma, pressure_ar1=rho, pressure_offset_pa=offset,
                       pressure_drift_pa_per_pv=drift, pressure_interval_pv=interval)
    total = (N - 1) * interval
    t, dp = read_pressure(np.array([0.0, total]), np.array([dp0, dp0]), noise, np.random.default_rng(7))
    assert t.size == N
    assert np.allclose(np.diff(t), interval, rtol=0, atol=1e-9)
    e = (dp - offset - drift * t) / dp0 - 1.0  # the relative noise, by the documented reading equation

    se_mean = sigma * math.sqrt((1 + rho) / ((1 - rho) * N))
    assert abs(e.mean()) < 4 * se_mean
    se_var = sigma**2 * math.sqrt(2 * (1 + rho**2) / ((1 - rho**2) * N))
    assert abs(e.var() - sigma**2) < 4 * se_var
    se_r1 = math.sqrt((1 - rho**2) / N) + 1.0 / N
    assert abs(_autocorr(e, 1) - rho) < 4 * se_r1 + 2 * (1 + rho) / N  # + the O(1/N) bias of the estimator
    assert abs(_autocorr(e, 2) - rho**2) < 6 * math.sqrt((1 + rho**2) / N)


def test_pressure_noise_is_relative_to_the_signal():
    noise = NoiseModel(pressure_relative=0.05, pressure_ar1=0.5, pressure_offset_pa=0.0,
                       pressure_drift_pa_per_pv=0.0, pressure_interval_pv=0.01)
    half = N // 2
    total = (N - 1) * 0.01
    pv = np.array([0.0, (half - 1) * 0.01, half * 0.01, total])
    dp = np.array([1.0e3, 1.0e3, 4.0e3, 4.0e3])
    t, reading = read_pressure(pv, dp, noise, np.random.default_rng(3))
    low, high = reading[: half - 1] - 1.0e3, reading[half + 1:] - 4.0e3
    assert low.std() == pytest.approx(0.05 * 1.0e3, rel=0.03)
    assert high.std() == pytest.approx(0.05 * 4.0e3, rel=0.03)


def test_tube_reading_errors_are_independent_uniform_within_half_a_graduation():
    rng = np.random.default_rng(11)
    true = rng.uniform(0.5, 3.0, N)  # away from the clipping limits 0 and the tube volume
    r = 0.2
    e = read_oil_volumes(true, 3.5, r, np.random.default_rng(5)) - true
    assert np.all(np.abs(e) <= r / 2 + 1e-12)
    assert e.min() < -0.499 * r and e.max() > 0.499 * r  # the full width is used
    var_u = r**2 / 12
    assert abs(e.mean()) < 4 * math.sqrt(var_u / N)
    se_var = math.sqrt((r**4 / 80 - var_u**2) / N)  # Var of a squared uniform deviate: E[e^4] - (E[e^2])^2
    assert abs(e.var() - var_u) < 4 * se_var
    assert abs(_autocorr(e, 1)) < 4 / math.sqrt(N)


def test_tube_without_oil_reads_zero_and_full_tube_stays_full():
    readings = read_oil_volumes(np.array([0.0, 3.5, 3.5]), 3.5, 0.2, np.random.default_rng(0))
    assert readings[0] == 0.0
    assert np.all(readings[1:] <= 3.5) and np.all(readings[1:] >= 3.4)


@pytest.mark.parametrize("field, value, allowed", [
    ("pressure_ar1", 1.0, "[0, 1)"),
    ("pressure_relative", -0.1, "[0, 1]"),
    ("tube_pv", 0.0, "(0, 1] PV"),
    ("oil_resolution_ml", float("nan"), "[0, 100] ml"),
    ("dead_volume_ml", "2", "[0, 10000] ml"),
])
def test_noise_model_rejects_bad_fields_naming_field_and_range(field, value, allowed):
    with pytest.raises(ValueError) as err:
        NoiseModel(**{field: value})
    assert field in str(err.value) and allowed in str(err.value)


def test_noise_model_from_mapping_rejects_unknown_fields():
    with pytest.raises(ValueError, match="unknown NoiseModel field"):
        NoiseModel.from_mapping({"pressure_noise": 0.1})
