"""Monte Carlo first-order and total Sobol indices of any vectorised function of independent inputs, by pick-freeze
sampling (Saltelli et al. 2010, "Variance based sensitivity analysis of model output. Design and estimator for the
total sensitivity index", Comput. Phys. Commun. 181, 259-270; Jansen 1999, Comput. Phys. Commun. 117, 35-43).

For a model whose Sobol indices have no closed form -- a Kriging predictor, whose Gaussian-process part is not a
polynomial of the inputs -- the indices are estimated from f at n (d + 2) points of a Saltelli design: the screening's
SALib wrappers (:func:`spflow.plugins.screening.sobol.sobol_sample` with the marginals ``inputs``, so the design is
drawn from them -- uniform, normal, lognormal, beta, truncated normal alike -- and
:func:`~spflow.plugins.screening.sobol.sobol_indices`, Saltelli et al. (2010)'s first-order and Jansen's total
estimator, thesis Eqs. 3.2-3.3). This module adds what a predictor needs on top:

* ``replicates`` independent scramblings (seeds spawned from ``seed``) give independent estimates; the result is their
  mean and the standard error of that mean, std(ddof = 1)/sqrt(replicates) (SALib's bootstrap intervals of one design
  are not used);
* f is evaluated block by block (n points at a time), so a Kriging predictor's cross-covariance stays (n, N);
* an output whose values do not vary has undefined (NaN) indices, as in :mod:`.sobol_from_pce` (the screening reports
  0 for such a QoI).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import NamedTuple

import numpy as np

from spflow.core.errors import ParameterError
from spflow.plugins.screening.salib_glue import is_constant
from spflow.plugins.screening.sobol import sobol_indices, sobol_sample

__all__ = ["SampledSobol", "pick_freeze_indices", "N_BASE", "REPLICATES"]

#: Default base sample size n (points per block; f is evaluated at n (d + 2) points per replicate).
N_BASE = 8192
#: Default number of independent scramblings.
REPLICATES = 4


class SampledSobol(NamedTuple):
    """The mean over the replicates of the first-order and total indices and their standard errors, each (m, d)."""

    first: np.ndarray
    total: np.ndarray
    first_se: np.ndarray
    total_se: np.ndarray


def _integer(value) -> int | None:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
        return None
    return int(value)


def _check_sampling(n_base, replicates, seed, what: str) -> tuple[int, int, int]:
    """(n_base, replicates, seed) as integers, or a ParameterError naming ``what``'s argument and its allowed range:
    ``n_base`` a power of 2 >= 64 (the balance of the Sobol' sequence), ``replicates`` >= 2 (a standard error needs
    two), ``seed`` a non-negative integer."""
    n = _integer(n_base)
    if n is None or n < 64 or n & (n - 1):
        raise ParameterError(f"{what}: n_base must be a power of 2 >= 64 (base points of the Sobol' design), got "
                             f"{n_base!r}")
    r = _integer(replicates)
    if r is None or r < 2:
        raise ParameterError(f"{what}: replicates must be an integer >= 2 (independent scramblings; the standard "
                             f"error needs two), got {replicates!r}")
    s = _integer(seed)
    if s is None or s < 0:
        raise ParameterError(f"{what}: seed must be a non-negative integer, got {seed!r}")
    return n, r, s


def _values(func: Callable[[np.ndarray], np.ndarray], x: np.ndarray, what: str) -> np.ndarray:
    """f at ``x`` (n, d) as (n, m), checked: n rows, finite."""
    y = np.asarray(func(x), dtype=float)
    if y.ndim not in (1, 2) or y.shape[0] != x.shape[0]:
        raise ParameterError(f"{what}: the function must return shape (n,) or (n, m) for n = {x.shape[0]} points, "
                             f"got {y.shape}")
    if not np.isfinite(y).all():
        raise ParameterError(f"{what}: the function returned a non-finite value; Sobol indices need finite outputs")
    return y.reshape(x.shape[0], -1)


def _one_replicate(func, inputs, n: int, rng: np.random.Generator, what: str) -> tuple[np.ndarray, np.ndarray]:
    """(first, total), each (m, d), from one scrambled Saltelli design of ``n`` base points (NaN for an output that
    does not vary)."""
    d = len(inputs)
    names = [f"x{j}" for j in range(d)]
    # with marginals, the design is drawn on the unit cube and mapped through them: the box arguments are not used
    x = sobol_sample(names, np.zeros(d), np.ones(d), n, seed=rng, inputs=inputs)
    y = np.concatenate([_values(func, x[k:k + n], what) for k in range(0, len(x), n)])
    indices = sobol_indices(y, names, resamples=2, seed=rng)  # its bootstrap is not used (module docstring)
    undefined = is_constant(y)[:, None]
    return (np.where(undefined, np.nan, indices["S1"].values), np.where(undefined, np.nan, indices["ST"].values))


def pick_freeze_indices(func: Callable[[np.ndarray], np.ndarray], inputs, n_base: int = N_BASE,
                        replicates: int = REPLICATES, seed: int = 0, what: str = "Sobol indices") -> SampledSobol:
    """First-order and total Sobol indices of ``func`` (points (k, d) in physical units -> values (k,) or (k, m))
    under the independent marginals ``inputs`` (:mod:`.input_marginals`), estimated by pick-freeze on ``replicates``
    independent scramblings of a Sobol' design of ``n_base`` base points (module docstring); f is called
    replicates (d + 2) times with n_base points. ``what`` names the caller in the errors."""
    n, r, s = _check_sampling(n_base, replicates, seed, what)
    inputs = list(inputs)
    estimates = [_one_replicate(func, inputs, n, np.random.default_rng(child), what)
                 for child in np.random.SeedSequence(s).spawn(r)]
    first, total = (np.array(e) for e in zip(*estimates))  # (replicates, m, d)
    first_se, total_se = (e.std(axis=0, ddof=1) / np.sqrt(r) for e in (first, total))
    return SampledSobol(first.mean(axis=0), total.mean(axis=0), first_se, total_se)
