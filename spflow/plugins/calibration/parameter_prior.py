"""The prior of the calibrated parameters θ: independent marginals, one per parameter (issue #24).

The thesis's prior is uniform on the box (Eq. 4.2). A parameter space may instead record a marginal law per
parameter (``distribution`` / ``distribution_parameters``, e.g. the ``priors`` stage's truncated normals fitted to the
lab data; :mod:`spflow.plugins.surrogates.input_marginals`), whose support is then the parameter's range. The log
prior density is the sum of the marginals' log densities,

    log p(θ) = Σ_j log p_j(θ_j),

−inf outside the supports. A uniform marginal contributes the constant −log(upper − lower), computed as the
thesis's box prior always was, so a prior of uniform marginals gives the same log posterior to the last bit as the
box. Prior draws (the samplers' starting points, ArviZ's ``prior`` group) go through each marginal's quantile
function from the same uniform random numbers a box draw uses, so they too are unchanged for uniform marginals.
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from spflow.core.errors import ParameterError
from spflow.plugins.surrogates.input_marginals import (Marginal, Uniform, from_unit_hypercube, marginal_variables,
                                                       marginals_from_dataset)
from spflow.plugins.surrogates.training_data import space_marginals

__all__ = ["ParameterPrior"]


class ParameterPrior:
    """Independent marginals ``inputs`` of the parameters ``names``, each on a bounded support; ``note`` says what was
    assumed ("" when the marginals were given)."""

    def __init__(self, names: list[str], inputs: list[Marginal], note: str = ""):
        if len(inputs) != len(names):
            raise ParameterError(f"prior: one marginal per parameter {list(names)} needed, got {len(inputs)}")
        self.names, self.inputs, self.note = list(names), list(inputs), note
        support = np.array([m.support for m in self.inputs], dtype=float).reshape(-1, 2)
        if not np.isfinite(support).all():
            k = int(np.flatnonzero(~np.isfinite(support).all(axis=1))[0])
            raise ParameterError(f"prior of {self.names[k]!r}: {self.inputs[k]!r} has the unbounded support "
                                 f"{self.inputs[k].support_text()}; a calibration prior needs a bounded one (uniform, "
                                 f"truncated_normal or beta on the parameter's range)")
        #: The supports, (d,) each: the box the sampler moves in.
        self.lower, self.upper = support[:, 0], support[:, 1]
        uniform = np.array([type(m) is Uniform for m in self.inputs], dtype=bool)
        # the uniform marginals' constant, as the box prior -sum(log(upper - lower)) of Eq. 4.2
        self._constant = -float(np.sum(np.log(self.upper[uniform] - self.lower[uniform])))
        self._densities = [(j, self.inputs[j].frozen()) for j in np.flatnonzero(~uniform)]

    @classmethod
    def box(cls, names: list[str], lower, upper, note: str = "") -> ParameterPrior:
        """Uniform on [lower, upper] (Eq. 4.2)."""
        return cls(names, [Uniform(lo, hi) for lo, hi in zip(lower, upper)], note)

    @classmethod
    def of_space(cls, space: xr.Dataset, where: str) -> ParameterPrior:
        """The prior a parameter ``space`` gives its parameters (in its ``param`` order): the marginals it records, or
        uniform on its box when it records none (said in :attr:`note`)."""
        names = [str(n) for n in space["param"].values]
        lower, upper = space["lower"].values.astype(float), space["upper"].values.astype(float)
        inputs = space_marginals(space, names, lower, upper, where)
        if inputs is None:
            return cls.box(names, lower, upper, "the space records no marginals: every parameter is uniform on its "
                                                "range (Eq. 4.2)")
        return cls(names, inputs)

    @classmethod
    def of_posterior(cls, posterior: xr.Dataset, where: str) -> ParameterPrior:
        """The prior a posterior Dataset records (:meth:`variables`), or uniform on its ``lower``/``upper`` for one
        written before the marginals were recorded."""
        names = [str(n) for n in posterior["param"].values]
        inputs = marginals_from_dataset(posterior, where)
        if inputs is None:
            return cls.box(names, posterior["lower"].values.astype(float), posterior["upper"].values.astype(float),
                           "the posterior records no prior marginals: taken as uniform on its lower..upper")
        return cls(names, inputs)

    @property
    def uniform(self) -> bool:
        """True when every marginal is uniform (the box prior of Eq. 4.2)."""
        return not self._densities

    def log_density(self, theta: np.ndarray) -> np.ndarray:
        """log p(θ) of each row of ``theta`` (rows, d): the sum of the marginals' log densities (−inf outside)."""
        theta = np.atleast_2d(theta)
        inside = np.all((theta >= self.lower) & (theta <= self.upper), axis=1)
        out = np.where(inside, self._constant, -np.inf)
        for j, law in self._densities:
            out += law.logpdf(theta[:, j])
        return out

    def sample(self, shape: tuple[int, ...], rng: np.random.Generator) -> np.ndarray:
        """Independent prior draws, shape ``shape`` + (d,): uniform numbers on [0, 1)^d through each marginal's
        quantile function (for a uniform marginal lower + (upper − lower) u, bit for bit the value
        ``rng.uniform(lower, upper)`` draws from the same generator state)."""
        u = rng.random((int(np.prod(shape)), len(self.names)))
        return from_unit_hypercube(self.inputs, u).reshape(*shape, len(self.names))

    def variables(self) -> dict:
        """The Dataset variables recording the marginals along ``param`` (as a space or a surrogate records them)."""
        return marginal_variables(self.inputs)

    def describe(self) -> str:
        """One line per parameter: its name and marginal law."""
        return "\n".join(f"{n} ~ {m!r}" for n, m in zip(self.names, self.inputs))
