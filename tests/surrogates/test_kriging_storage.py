"""Kriging surrogates round-trip through netCDF without pickle: load_surrogate rebuilds the Cholesky factors from the
stored training data and hyperparameters and predicts identically; a store missing them is rejected."""

import numpy as np
import pytest
import xarray as xr

from spflow.core.errors import SchemaError
from spflow.plugins.surrogates.contract import SURROGATE, load_surrogate
from spflow.plugins.surrogates.gp_model import GP
from spflow.plugins.surrogates.outputs import OutputIndex
from spflow.plugins.surrogates.pck_model import PCK

NAMES = ["k", "mu"]
LOWER, UPPER = np.array([1.0, 0.5]), np.array([3.0, 2.0])


def _data():
    rng = np.random.default_rng(11)
    x = LOWER + (UPPER - LOWER) * rng.uniform(size=(25, 2))
    y = np.c_[x[:, 0] ** 2 / x[:, 1], np.log(x[:, 0]) + np.sin(2 * x[:, 1]), x[:, 0] * x[:, 1]]
    outputs = OutputIndex(np.array(["dp", "dp", "recovery"]), np.array(["BCF1"] * 3), np.array([0.1, 0.2, np.nan]),
                          {"dp": "Pa", "recovery": "1"})
    return x, y, outputs


@pytest.mark.parametrize("kind", ["pck", "gp"])
def test_netcdf_round_trip_predicts_identically(tmp_path, kind):
    x, y, outputs = _data()
    if kind == "pck":
        model = PCK.fit(NAMES, LOWER, UPPER, outputs, x, y, degree_max=2, kernel="matern52", share="variable",
                        restarts=2, seed=5)
    else:
        model = GP.fit(NAMES, LOWER, UPPER, outputs, x, y, restarts=2, seed=5)
    ds = model.to_dataset()
    SURROGATE.validate(ds, stage="test", port="surrogate")
    assert ds.attrs["surrogate"] == kind and ds.attrs["units_dp"] == "Pa"
    path = tmp_path / f"{kind}.nc"
    ds.to_netcdf(path)
    with xr.open_dataset(path) as stored:
        loaded = load_surrogate(stored.load())
    assert type(loaded) is type(model)
    xt = LOWER + (UPPER - LOWER) * np.random.default_rng(2).uniform(size=(40, 2))
    mean, var = model.predict(xt)
    mean2, var2 = loaded.predict(xt)
    np.testing.assert_array_equal(mean2, mean)
    np.testing.assert_array_equal(var2, var)
    np.testing.assert_array_equal(loaded.loo, model.loo)
    xr.testing.assert_identical(loaded.predict_dataset(xt), model.predict_dataset(xt))


def test_store_without_hyperparameters_is_rejected():
    x, y, outputs = _data()
    ds = GP.fit(NAMES, LOWER, UPPER, outputs, x, y, restarts=1).to_dataset()
    with pytest.raises(SchemaError, match="lengthscale"):
        load_surrogate(ds.drop_vars("lengthscale"))
    no_kernel = ds.copy(deep=True)
    del no_kernel.attrs["kernel"]
    with pytest.raises(SchemaError, match="kernel"):
        load_surrogate(no_kernel)
