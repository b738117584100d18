"""The ``pce`` surrogate kind: exact reproduction of polynomials, the corrected-LOO error variance it reports, blockwise
evaluation, and the xarray/netCDF round trip through ``load_surrogate``."""

import numpy as np
import pytest
import xarray as xr

from spflow.core.errors import ParameterError
from spflow.plugins.surrogates.basis import design_matrix
from spflow.plugins.surrogates.contract import load_surrogate
from spflow.plugins.surrogates.outputs import OutputIndex
from spflow.plugins.surrogates.pce_model import PCE

LOWER, UPPER = np.array([2.0, -1.0, 10.0]), np.array([5.0, 3.0, 20.0])
OUTPUTS = OutputIndex(np.array(["a", "a", "b"]), np.array(["E1", "E1", "E1"]), np.array([0.0, 0.5, np.nan]),
                      {"a": "Pa", "b": "1"})


def _f(x):
    """Three outputs: two cubic polynomials and one smooth non-polynomial function of the physical inputs."""
    return np.column_stack([1 + x[:, 0] * x[:, 1] - 0.01 * x[:, 2] ** 2,
                            x[:, 0] ** 3 / 10 + x[:, 1] * x[:, 2] / 5,
                            np.exp(0.3 * x[:, 1]) * np.sin(x[:, 2] / 4)])


def _x(n, seed):
    return np.random.default_rng(seed).uniform(LOWER, UPPER, (n, 3))


@pytest.fixture(scope="module")
def model():
    x = _x(120, 0)
    return PCE.fit(["p", "q", "r"], LOWER, UPPER, OUTPUTS, x, _f(x), degree_max=5, q=1.0, solver="ols")


def test_reproduces_polynomials_and_reports_loo_error_variance(model):
    x = _x(50, 1)
    mean, var = model.predict(x)
    np.testing.assert_allclose(mean[:, :2], _f(x)[:, :2], rtol=1e-9, atol=1e-9)
    assert np.abs(mean[:, 2] - _f(x)[:, 2]).max() < 0.05
    # the reported variance: per output corrected eps*_LOO * Var(y_train), constant in x
    y_train = _f(_x(120, 0))
    np.testing.assert_allclose(var, np.broadcast_to(model.modified_loo * y_train.var(axis=0), var.shape))
    assert var[0, 2] > 0 and np.all(var[:, :2] < 1e-20)


def test_blockwise_prediction_equals_one_design_matrix(model):
    x = _x(1300, 2)  # more than one block of points
    direct = design_matrix(model.to_unit(x), model.indices) @ model.coefficients.T
    np.testing.assert_allclose(model.predict(x)[0], direct, rtol=1e-13, atol=1e-12)


def test_netcdf_round_trip_gives_identical_predictions(model, tmp_path):
    ds = model.to_dataset()
    assert ds.attrs["surrogate"] == "pce" and ds["coefficients"].dims == ("output", "term")
    assert ds["multi_index"].dims == ("term", "param")
    for name in ("loo", "modified_loo", "empirical"):
        assert ds[name].dims == ("output",) and ds[name].attrs["units"] == "1"
    ds.to_netcdf(tmp_path / "pce.nc")
    with xr.open_dataset(tmp_path / "pce.nc") as stored:
        again = load_surrogate(stored.load())
    assert isinstance(again, PCE)
    x = _x(40, 3)
    for a, b in zip(model.predict(x), again.predict(x)):
        np.testing.assert_array_equal(a, b)
    np.testing.assert_array_equal(again.moments()[1], model.moments()[1])
    assert again.info == model.info and again.names == model.names
    np.testing.assert_array_equal(again.outputs.pv, model.outputs.pv)


def test_predict_dataset_labels(model):
    ds = model.predict_dataset(_x(4, 4))
    assert ds["mean"].dims == ("sample", "output")
    assert list(ds["output_variable"].values) == ["a", "a", "b"] and ds.attrs["units_a"] == "Pa"


def test_bad_input(model):
    with pytest.raises(ParameterError, match=r"shape \(n, 3\)"):
        model.predict(np.zeros((2, 4)))
    with pytest.raises(ParameterError, match="finite"):
        model.predict(np.full((1, 3), np.nan))
    with pytest.raises(ParameterError, match="one column per parameter"):
        PCE.fit(["p", "q"], LOWER[:2], UPPER[:2], OUTPUTS, _x(20, 0), _f(_x(20, 0)))
    with pytest.raises(ParameterError, match="unit box"):
        PCE.fit(["p", "q", "r"], LOWER, UPPER, OUTPUTS, _x(20, 0) + 100.0, _f(_x(20, 0)))
    with pytest.raises(ParameterError, match="degree_max"):
        PCE.fit(["p", "q", "r"], LOWER, UPPER, OUTPUTS, _x(20, 0), _f(_x(20, 0)), degree_max=0)
    with pytest.raises(ParameterError, match="coefficients"):
        PCE(["p", "q", "r"], LOWER, UPPER, OUTPUTS, model.indices, model.coefficients[:2], model.loo,
            model.modified_loo, model.empirical, model.output_variance, model.info)
