"""The posterior Dataset that both MCMC samplers produce and the diagnostics, figures and predictive stage read.

ArviZ-compatible layout (``az.convert_to_dataset`` / ``az.rhat`` read it as is): draws of the model parameters θ as
``theta`` (chain, draw, param), of the per-QoI noise σ_i of Eq. 4.3 as ``sigma`` (chain, draw, block), the log
likelihood and log posterior per draw, and sampler statistics (``acceptance`` per chain). The prior box (Eq. 4.2)
travels along as ``lower``/``upper`` and each parameter's prior law as ``distribution`` / ``distribution_parameters``
(:func:`~spflow.plugins.surrogates.input_marginals.marginal_variables`; absent in a posterior written before they were
recorded, which then reads as uniform on the box), so that prior-vs-posterior plots and the predictive stage need
nothing else.
Each QoI block is labelled by its variable and experiment (``block_variable``, ``block_experiment``), its number of
points and its unit. Units are UDUNITS strings; θ, σ and the box have units per element (``unit``, ``block_units``;
:mod:`spflow.core.cf_metadata`), and every variable a ``long_name`` (:meth:`DatasetSchema.annotate`).
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from spflow.core.cf_metadata import udunits
from spflow.core.schema import DatasetSchema, Variable
from spflow.plugins.design.parameter_map import ParameterMap
from spflow.plugins.surrogates.input_marginals import MARGINAL_SCHEMA

__all__ = ["POSTERIOR", "posterior_dataset", "flat_theta", "block_labels"]

#: Schema of an MCMC posterior. θ and the prior box have units per parameter (``unit``), σ per block
#: (``block_units``): :mod:`spflow.core.cf_metadata`.
POSTERIOR = DatasetSchema(
    dims=("chain", "draw", "param", "block"),
    variables={
        "theta": Variable(("chain", "draw", "param"), units_variable="unit",
                          long_name="posterior draws of the calibrated parameters (design columns)"),
        "sigma": Variable(("chain", "draw", "block"), units_variable="block_units",
                          long_name="posterior draws of the noise standard deviation of each block (Eq. 4.3)"),
        "log_likelihood": Variable(("chain", "draw"), units="1", long_name="log likelihood (natural log)"),
        "log_posterior": Variable(("chain", "draw"), units="1", long_name="log posterior density (natural log)"),
        "acceptance": Variable(("chain",), units="1", long_name="acceptance fraction of the chain"),
        "lower": Variable(("param",), units_variable="unit", long_name="lower end of the prior's support (Eq. 4.2)"),
        "upper": Variable(("param",), units_variable="unit", long_name="upper end of the prior's support (Eq. 4.2)"),
        **MARGINAL_SCHEMA,
        "unit": Variable(("param",), kind="U", long_name="UDUNITS unit of each parameter's design column"),
        "block_variable": Variable(("block",), kind="U", long_name="QoI of the block"),
        "block_experiment": Variable(("block",), kind="U", long_name="coreflood of the block"),
        "block_points": Variable(("block",), kind="i", units="1", long_name="observations in the block"),
        "block_units": Variable(("block",), kind="U", long_name="UDUNITS unit of the block's QoI"),
        "chain": Variable(("chain",), kind="i", units="1", long_name="MCMC chain number"),
        "draw": Variable(("draw",), kind="i", units="1", long_name="kept draw number"),
        "param": Variable(("param",), kind="UO", long_name="calibrated parameter (design column)"),
        "block": Variable(("block",), kind="UO", long_name="QoI block: variable/experiment"),
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
                      chain_coords: dict | None = None, prior: dict | None = None) -> xr.Dataset:
    """Assemble the posterior Dataset from arrays (chain, draw, ...) of one sampler run; it carries the space's
    parameter map (:mod:`spflow.plugins.design.parameter_map`), so draws become forward-model parameters downstream
    (``posterior_predictive``, ``slug_design``), and ``prior``, the variables recording the prior's marginals
    (:meth:`.ParameterPrior.variables`)."""
    names = [str(n) for n in space["param"].values]
    ds = xr.Dataset(
        {
            "theta": (("chain", "draw", "param"), theta),
            "sigma": (("chain", "draw", "block"), sigma),
            "log_likelihood": (("chain", "draw"), log_likelihood, {"units": "1"}),
            "log_posterior": (("chain", "draw"), log_posterior, {"units": "1"}),
            "acceptance": ("chain", acceptance, {"units": "1"}),
            "lower": ("param", space["lower"].values),
            "upper": ("param", space["upper"].values),
            "unit": ("param", np.array([udunits(u) for u in space["unit"].values])),
            "block_variable": ("block", np.array([v for v, _ in pairs])),
            "block_experiment": ("block", np.array([e for _, e in pairs])),
            "block_points": ("block", np.asarray(points, dtype=np.int64), {"units": "1"}),
            "block_units": ("block", np.array([udunits(u) for u in units])),
            **(prior or {}),
        },
        coords={"chain": ("chain", np.arange(theta.shape[0]), {"units": "1"}),
                "draw": ("draw", np.arange(theta.shape[1]), {"units": "1"}), "param": names,
                "block": block_labels(pairs), **(chain_coords or {})},
        attrs=dict(attrs),
    )
    return POSTERIOR.annotate(ParameterMap.of(space).attach(ds))


def flat_theta(posterior: xr.Dataset) -> np.ndarray:
    """All draws of θ as an array (chain·draw, param)."""
    theta = posterior["theta"].transpose("chain", "draw", "param").values
    return theta.reshape(-1, theta.shape[-1])
