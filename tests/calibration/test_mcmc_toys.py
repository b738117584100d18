"""Toy surrogates with known answers for the MCMC tests (a linear model f(θ) = Aθ + b with a constant error variance),
and the synthetic observations they are compared with. Imported by the other ``test_mcmc_*`` files; the tests here
check the toy itself (prediction and round trip through the surrogate contract)."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

from spflow.plugins.surrogates.contract import Surrogate, load_surrogate
from spflow.plugins.surrogates.outputs import OutputIndex

from surrogate_kind_plugin import surrogate_kinds_registered


class LinearToy(Surrogate):
    """f(θ) = A θ + b with predict variance ``var`` (constant in θ)."""

    kind = "test_mcmc_linear"

    def __init__(self, names, lower, upper, outputs, a, b, var):
        super().__init__(names, lower, upper, outputs)
        self.a, self.b, self.var = np.asarray(a, float), np.asarray(b, float), np.asarray(var, float)

    def _predict(self, x):
        return x @ self.a.T + self.b, np.broadcast_to(self.var, (x.shape[0], self.b.size)).copy()

    def to_dataset(self):
        return self._dataset({"a": (("output", "param"), self.a), "b": ("output", self.b),
                              "var": ("output", self.var)})

    @classmethod
    def from_dataset(cls, ds):
        return cls(**cls._common(ds), a=ds["a"].values, b=ds["b"].values, var=ds["var"].values)


@pytest.fixture(autouse=True, scope="module")
def toy_kind_registered():
    with surrogate_kinds_registered(LinearToy, name="test_mcmc_toys_kind"):
        yield


def outputs_for(blocks: dict[tuple[str, str], int]) -> OutputIndex:
    """Output labels: for each (variable, experiment), that many points on the 0.1 PV grid (from PV 0.1)."""
    var, exp, pv = [], [], []
    for (v, e), n in blocks.items():
        var += [v] * n
        exp += [e] * n
        pv += list(np.round(0.1 * np.arange(1, n + 1), 10))
    return OutputIndex(np.array(var), np.array(exp), np.array(pv), {"dp": "Pa", "oil_cut": "1"})


def observations_for(index: OutputIndex, values: np.ndarray) -> xr.Dataset:
    """An observations Dataset (experiment, pv) holding ``values`` at the labels of ``index``."""
    experiments = sorted(set(index.experiment.tolist()))
    grid = np.round(np.unique(index.pv), 10)
    data = {v: np.full((len(experiments), grid.size), np.nan) for v in set(index.variable.tolist())}
    for k in range(len(index)):
        data[index.variable[k]][experiments.index(index.experiment[k]), np.searchsorted(grid, index.pv[k])] = values[k]
    ds = xr.Dataset({v: (("experiment", "pv"), d, {"units": index.units[v]}) for v, d in data.items()}
                    | {"total_pv": ("experiment", np.full(len(experiments), grid[-1]), {"units": "1"})},
                    coords={"experiment": experiments, "pv": grid})
    ds["pv"].attrs["units"] = "1"
    return ds


def space_for(names, lower, upper) -> xr.Dataset:
    """A SPACE Dataset for the given box."""
    lower, upper = np.asarray(lower, float), np.asarray(upper, float)
    return xr.Dataset({"lower": ("param", lower, {"units": "1"}), "upper": ("param", upper, {"units": "1"}),
                       "default": ("param", 0.5 * (lower + upper), {"units": "1"}),
                       "unit": ("param", np.array(["1"] * len(names)))}, coords={"param": list(names)})


def test_linear_toy_predicts_and_round_trips_through_a_dataset():
    rng = np.random.default_rng(0)
    index = outputs_for({("dp", "BCF1"): 4, ("oil_cut", "BCF1"): 3})
    a, b = rng.normal(size=(7, 2)), rng.normal(size=7)
    toy = LinearToy(["p", "q"], [-1, -1], [1, 1], index, a, b, np.full(7, 0.25))
    x = rng.uniform(-1, 1, (5, 2))
    again = load_surrogate(toy.to_dataset())
    np.testing.assert_array_equal(again.predict(x)[0], x @ a.T + b)
    np.testing.assert_array_equal(again.predict(x)[1], np.full((5, 7), 0.25))


def test_observations_sit_at_the_labels():
    index = outputs_for({("dp", "BCF1"): 4, ("oil_cut", "BCF1"): 3})
    obs = observations_for(index, np.arange(7.0))
    np.testing.assert_array_equal(obs["dp"].sel(experiment="BCF1").values, [0, 1, 2, 3])
    np.testing.assert_array_equal(obs["oil_cut"].sel(experiment="BCF1").values[:3], [4, 5, 6])
    assert np.isnan(obs["oil_cut"].sel(experiment="BCF1").values[3])
