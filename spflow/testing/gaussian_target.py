"""A posterior with a known answer for sampler checks: a linear model f(θ) = A θ + c of two parameters observed at
eight points with known Gaussian noise σ, under the uniform prior of a box.

With ``noise="known"`` and no surrogate variance the likelihood of thesis Eq. 4.3 is Gaussian in θ, so inside a box
far wider than it the posterior is the 2-D normal N(μ, Σ) with Σ = σ² (AᵀA)⁻¹ and μ = Σ Aᵀ(d − c) / σ² (least
squares). The rows of A are (1, t_k) with t_k in [0.2, 1.6], which correlates the two parameters (ρ ≈ −0.89). The
model is a surrogate kind of its own (``spflow_testing_linear``), registered for the duration of a check through the
same hook a plugin uses.
"""

from __future__ import annotations

import contextlib
from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np
import xarray as xr

from spflow.core.hookspecs import hookimpl
from spflow.core.plugins import get_registry, register_plugin, unregister_plugin
from spflow.plugins.surrogates.contract import Surrogate
from spflow.plugins.surrogates.outputs import OutputIndex

__all__ = ["LinearModel", "GaussianTarget", "gaussian_target", "linear_kind_registered"]

#: The plugin name the linear kind is registered under during a check.
PLUGIN_NAME = "spflow.testing linear model"


class LinearModel(Surrogate):
    """f(θ) = A θ + c, with zero predicted variance."""

    kind = "spflow_testing_linear"

    def __init__(self, names, lower, upper, outputs, a, c):
        super().__init__(names, lower, upper, outputs)
        self.a, self.c = np.asarray(a, dtype=float), np.asarray(c, dtype=float)

    def _predict(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        mean = x @ self.a.T + self.c
        return mean, np.zeros_like(mean)

    def to_dataset(self) -> xr.Dataset:
        return self._dataset({"a": (("output", "param"), self.a, {"units": "per-parameter"}),
                              "c": ("output", self.c, {"units": "Pa"})})

    @classmethod
    def from_dataset(cls, ds: xr.Dataset) -> LinearModel:
        return cls(**cls._common(ds), a=ds["a"].values, c=ds["c"].values)


class _LinearKindPlugin:
    @hookimpl
    def spflow_register_surrogate_kinds(self, register):
        register(LinearModel)


@contextlib.contextmanager
def linear_kind_registered() -> Iterator[None]:
    """The linear kind loadable by ``load_surrogate`` inside the block (left as it was if already registered)."""
    if get_registry().surrogate_kinds.get(LinearModel.kind) is LinearModel:
        yield
        return
    register_plugin(_LinearKindPlugin(), name=PLUGIN_NAME)
    try:
        yield
    finally:
        unregister_plugin(PLUGIN_NAME)


@dataclass(frozen=True)
class GaussianTarget:
    """The sampler's inputs and parameters and the analytic posterior moments (inside a wide box)."""

    surrogate: xr.Dataset
    observations: xr.Dataset
    space: xr.Dataset
    params: dict
    mean: np.ndarray
    cov: np.ndarray

    @property
    def inputs(self) -> dict[str, xr.Dataset]:
        return {"surrogate": self.surrogate, "observations": self.observations, "space": self.space}


def gaussian_target(width: float = 10.0, cut: bool = False) -> GaussianTarget:
    """The target with a prior box of ``width`` posterior standard deviations either side of the mean; ``cut=True``
    moves the upper bound of the first parameter to its posterior mean, so that half the mass lies outside the box
    (draws must still stay inside)."""
    names, sigma, experiment = ["theta_1", "theta_2"], 0.1, "T1"
    t = np.linspace(0.2, 1.6, 8)
    a, c = np.column_stack([np.ones_like(t), t]), np.full(t.size, 1.0)
    truth = np.array([0.5, -0.3])
    noise = np.random.default_rng(20231).normal(0.0, sigma, t.size)
    observed = a @ truth + c + noise
    cov = sigma**2 * np.linalg.inv(a.T @ a)
    mean = cov @ a.T @ (observed - c) / sigma**2
    sd = np.sqrt(np.diag(cov))
    lower, upper = mean - width * sd, mean + width * sd
    if cut:
        upper[0] = mean[0]
    pv = np.round(0.1 * np.arange(1, t.size + 1), 10)
    outputs = OutputIndex(np.full(t.size, "dp"), np.full(t.size, experiment), pv, {"dp": "Pa"})
    model = LinearModel(names, mean - width * sd, mean + width * sd, outputs, a, c)
    observations = xr.Dataset({"dp": (("experiment", "pv"), observed[None, :], {"units": "Pa"}),
                               "total_pv": ("experiment", [pv[-1]], {"units": "PV"})},
                              coords={"experiment": [experiment], "pv": ("pv", pv, {"units": "PV"})})
    space = xr.Dataset({"lower": ("param", lower, {"units": "1"}), "upper": ("param", upper, {"units": "1"}),
                        "default": ("param", 0.5 * (lower + upper), {"units": "1"}),
                        "unit": ("param", np.array(["1", "1"]))}, coords={"param": names})
    params = {"experiments": [experiment], "variables": ["dp"], "noise": "known", "sigma": [sigma],
              "surrogate_variance": False}
    return GaussianTarget(model.to_dataset(), observations, space, params, mean, cov)
