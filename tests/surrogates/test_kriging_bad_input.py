"""Bad input to the Kriging surrogates fails with a ParameterError naming the field and what is allowed, before any
fitting work."""

import numpy as np
import pytest

import spflow.plugins.surrogates.kriging_surrogate as kriging_surrogate
import spflow.plugins.surrogates.pck_model as pck_model
from spflow.core.errors import ParameterError
from spflow.plugins.surrogates.gp_model import GP
from spflow.plugins.surrogates.kriging import UniversalKriging, correlation
from spflow.plugins.surrogates.outputs import OutputIndex
from spflow.plugins.surrogates.pck_model import PCK

NAMES = ["a", "b"]
LOWER, UPPER = np.zeros(2), np.ones(2)
OUT = OutputIndex(np.array(["f"]), np.array([""]), np.array([np.nan]), {"f": "1"})


def _xy(n=12):
    x = np.random.default_rng(0).uniform(size=(n, 2))
    return x, (x[:, 0] + np.sin(3 * x[:, 1]))[:, None]


@pytest.mark.parametrize(("options", "match"), [
    ({"mode": "best"}, r"mode 'best' is not known; allowed: \['sequential', 'optimal'\]"),
    ({"kernel": "cubic"}, r"kernel 'cubic' is not known; allowed: \['gaussian', 'matern52'\]"),
    ({"share": "all"}, r"share 'all' is not known; allowed: \['output', 'variable'\]"),
    ({"restarts": 0}, "restarts must be an integer >= 1"),
    ({"nugget": float("nan")}, r"nugget must be a number in \[0, 0.1\]"),
    ({"nugget": 0.5}, r"nugget must be a number in \[0, 0.1\]"),
])
def test_bad_fit_options_raise_before_the_pce_fit(monkeypatch, options, match):
    calls = []
    monkeypatch.setattr(pck_model, "fit_pce", lambda *a, **k: calls.append(a))
    x, y = _xy()
    with pytest.raises(ParameterError, match=match):
        PCK.fit(NAMES, LOWER, UPPER, OUT, x, y, **options)
    assert calls == []


@pytest.mark.parametrize(("kind", "bad", "match"), [
    (GP, {"y": "two columns"}, r"need x \(n, 2\) and y \(n, 1\)"),
    (PCK, {"y": "nan"}, "training x and y must be finite"),
    (GP, {"x": "outside"}, "training points must lie in the box"),
    (PCK, {"x": "two points"}, "at least 3 training points"),
])
def test_bad_training_data_raise_before_fitting(monkeypatch, kind, bad, match):
    calls = []
    monkeypatch.setattr(pck_model, "fit_pce", lambda *a, **k: calls.append(a))
    monkeypatch.setattr(kriging_surrogate, "fit_group", lambda *a, **k: calls.append(a))
    x, y = _xy()
    x = {"outside": x + [0.0, 0.5], "two points": x[:2]}.get(bad.get("x"), x)
    y = {"two columns": np.c_[y, y], "nan": np.where(np.arange(12)[:, None] == 3, np.nan, y)}.get(bad.get("y"), y)
    y = y[: x.shape[0]]
    with pytest.raises(ParameterError, match=match):
        kind.fit(NAMES, LOWER, UPPER, OUT, x, y)
    assert calls == []


def test_bad_prediction_points():
    x, y = _xy()
    model = GP.fit(NAMES, LOWER, UPPER, OUT, x, y, restarts=1)
    with pytest.raises(ParameterError, match=r"expected points of shape \(n, 2\)"):
        model.predict(np.zeros((3, 3)))
    with pytest.raises(ParameterError, match="finite"):
        model.predict(np.array([[0.5, np.inf]]))


def test_bad_hyperparameters_and_trends():
    with pytest.raises(ParameterError, match="kernel 'exp' is not known"):
        correlation("exp", np.zeros((2, 2)), np.zeros((2, 2)), np.ones(2))
    with pytest.raises(ParameterError, match="length scales must be .* positive"):
        correlation("gaussian", np.zeros((2, 2)), np.zeros((2, 2)), np.array([1.0, -0.5]))
    z = np.random.default_rng(1).uniform(-1, 1, (4, 1))
    basis = np.c_[np.ones(4), z, z**2, z**3]
    with pytest.raises(ParameterError, match=r"trend sizes must be in \[1, 3\]"):
        UniversalKriging(z, z, basis, np.ones((1, 4), bool), "gaussian", np.ones(1), 0.0)
    with pytest.raises(ParameterError, match="linearly dependent"):
        UniversalKriging(z, z, np.c_[np.ones(4), 2 * np.ones(4)], np.ones((1, 2), bool), "gaussian", np.ones(1),
                         0.0)
    x, y = _xy()
    model = GP.fit(NAMES, LOWER, UPPER, OUT, x, y, restarts=1)
    args = dict(names=NAMES, lower=LOWER, upper=UPPER, outputs=OUT, x=x, y=y, indices=model.indices,
                trend=model.trend, group=model.group, lengthscale=model.lengthscale, nugget=model.nugget,
                kernel="gaussian", info={})
    with pytest.raises(ParameterError, match=r"length scales must be \(group, 2\)"):
        GP(**{**args, "lengthscale": np.ones((1, 3))})
    with pytest.raises(ParameterError, match="nuggets must be >= 0"):
        GP(**{**args, "nugget": np.array([-1.0])})
    with pytest.raises(ParameterError, match="bounds must satisfy lower < upper"):
        GP(**{**args, "upper": np.array([1.0, 0.0])})
