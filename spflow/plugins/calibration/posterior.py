"""The posterior Dataset that both MCMC samplers produce and the diagnostics, figures and predictive stage read.

ArviZ-compatible layout (``az.convert_to_dataset`` / ``az.rhat`` read it as is): draws of the model parameters θ as
``theta`` (chain, draw, param), of the per-QoI noise σ_i of Eq. 4.3 as ``sigma`` (chain, draw, block), the log
likelihood and log posterior per draw, and sampler statistics (``acceptance`` per chain). The prior box (Eq. 4.2)
travels along as ``lower``/``upper`` so that prior-vs-posterior plots and the predictive stage need nothing else.
Each QoI block is labelled by its variable and experiment (``block_variable``, ``block_experiment``), its number of
points and its unit.
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from spflow.core.schema import DatasetSchema, Variable
from spflow.plugins.design.parameter_map import ParameterMap

__all__ = ["POSTERIOR", "posterior_dataset", "flat_theta", "block_labels"]

#: Schema of an MCMC posterior.
POSTERIOR = DatasetSchema(
    dims=("chain", "draw", "param", "block"),
    variables={
        "theta": Variable(("chain", "draw", "param"), units=None),
        "sigma": Variable(("chain", "draw", "block"), units=None),
        "log_likelihood": Variable(("chain", "draw"), units="1"),
        "log_posterior": Variable(("chain", "draw"), units="1"),
        "acceptance": Variable(("chain",), units="1"),
        "lower": Variable(("param",), units=None),
        "upper": Variable(("param",), units=None),
        "block_variable": Variable(("block",), kind="U"),
        "block_experiment": Variable(("block",), kind="U"),
    },
    attrs=("sampler", "noise"),
    doc="MCMC draws of the calibration parameters and noise levels (thesis §4.6)",
)


def block_labels(pairs: list[tuple[str, str]]) -> list[str]:
    """``variable/experiment`` labels of the QoI blocks."""
    return [f"{v}/{e}" for v, e in pairs]


def posterior_dataset(theta: np.ndarray, sigma: np.ndarray, log_likelihood: np.ndarray, log_posterior: np.ndarray,
                      acceptance: np.ndarray, *, space: xr.Dataset, pairs: list[tuple[str, str]],
                      points: list[int], units: list[str], attrs: dict,
                      chain_coords: dict | None = None) -> xr.Dataset:
    """Assemble the posterior Dataset from arrays (chain, draw, ...) of one sampler run; it carries the space's
    parameter map (:mod:`spflow.plugins.design.parameter_map`), so draws become forward-model parameters downstream
    (``posterior_predictive``, ``slug_design``)."""
    names = [str(n) for n in space["param"].values]
    ds = xr.Dataset(
        {
            "theta": (("chain", "draw", "param"), theta, {"units": "per-parameter (see unit)"}),
            "sigma": (("chain", "draw", "block"), sigma, {"units": "per-block (see block_units)"}),
            "log_likelihood": (("chain", "draw"), log_likelihood, {"units": "1"}),
            "log_posterior": (("chain", "draw"), log_posterior, {"units": "1"}),
            "acceptance": ("chain", acceptance, {"units": "1"}),
            "lower": ("param", space["lower"].values, {"units": "per-parameter (see unit)"}),
            "upper": ("param", space["upper"].values, {"units": "per-parameter (see unit)"}),
            "unit": ("param", space["unit"].values),
            "block_variable": ("block", np.array([v for v, _ in pairs])),
            "block_experiment": ("block", np.array([e for _, e in pairs])),
            "block_points": ("block", np.asarray(points, dtype=np.int64)),
            "block_units": ("block", np.asarray(units)),
        },
        coords={"chain": np.arange(theta.shape[0]), "draw": np.arange(theta.shape[1]), "param": names,
                "block": block_labels(pairs), **(chain_coords or {})},
        attrs=dict(attrs),
    )
    return ParameterMap.of(space).attach(ds)


def flat_theta(posterior: xr.Dataset) -> np.ndarray:
    """All draws of θ as an array (chain·draw, param)."""
    theta = posterior["theta"].transpose("chain", "draw", "param").values
    return theta.reshape(-1, theta.shape[-1])
