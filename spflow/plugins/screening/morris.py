"""Morris elementary effects with SALib: a cheaper screening than Sobol' (r (d + 1) runs for r trajectories).

``morris_sample`` wraps :func:`SALib.sample.morris.sample` (one-at-a-time trajectories on a ``levels``-level grid of
the box) and ``morris_indices`` wraps :func:`SALib.analyze.morris.analyze` for a matrix of evaluations, giving per
QoI and parameter mu (mean elementary effect), mu* (mean absolute effect, Campolongo et al. 2007), its bootstrap
interval half-width and sigma (spread of the effects: non-linearity or interactions). An elementary effect is the
QoI change over a step of Delta = levels / (2 (levels - 1)) of the parameter's range, divided by Delta, so mu, mu*
and sigma carry the QoI's unit ("per full range"). Under marginals (``inputs``) the trajectories are drawn on the
unit hypercube and mapped through the marginals' quantile functions (:mod:`.salib_glue`), so a step is Delta of the
parameter's probability scale (its cdf) and the effects are "per full range of the cdf" (Saltelli et al. 2008,
Global Sensitivity Analysis: The Primer, §3.3, for non-uniform inputs). Constant QoIs get zeros (:mod:`.salib_glue`).
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from spflow.core.cf_metadata import UNITS_VARIABLE
from spflow.core.errors import ParameterError

from .salib_glue import is_constant, salib_design, salib_problem

__all__ = ["check_morris_design", "morris_sample", "morris_indices"]

_KEYS = ("mu", "mu_star", "mu_star_conf", "sigma")


def check_morris_design(trajectories: int, levels: int, where: str = "Morris:") -> None:
    """Raise :class:`ParameterError` unless there are >= 2 trajectories and an even number of levels >= 2."""
    if trajectories < 2:
        raise ParameterError(f"{where} trajectories = {trajectories!r} must be >= 2 (mu* and sigma need several)")
    if levels < 2 or levels % 2:
        raise ParameterError(f"{where} levels = {levels!r} must be an even integer >= 2 (2, 4, 6, ...): the step "
                             "Delta = p / (2 (p - 1)) needs an even grid")


def morris_sample(names: list[str], lower: np.ndarray, upper: np.ndarray, trajectories: int, *, levels: int = 4,
                  seed: int | np.random.Generator | None = None, inputs=None) -> np.ndarray:
    """The (trajectories (d + 1), d) Morris design on the box (physical units), in SALib's row order; with ``inputs``
    (one marginal per name) the grid is one of the marginals' quantiles (module docstring)."""
    from SALib.sample import morris as morris_sampler  # SALib loads when a design is drawn

    check_morris_design(trajectories, levels)
    return salib_design(lambda problem: morris_sampler.sample(problem, trajectories, num_levels=levels, seed=seed),
                        names, lower, upper, inputs)


def morris_indices(x: np.ndarray, y: np.ndarray, names: list[str], lower: np.ndarray, upper: np.ndarray, *,
                   levels: int = 4, conf_level: float = 0.95, resamples: int = 100,
                   seed: int | np.random.Generator | None = None) -> xr.Dataset:
    """mu, mu_star, mu_star_conf, sigma (``qoi``, ``param``) and the QoI ``variance`` (``qoi``) from a
    :func:`morris_sample` design ``x`` and its evaluations ``y`` (n_runs, n_qoi).

    The elementary effects are SALib's unscaled ones, output differences over the step on the unit-scaled box (on
    the marginals' cdf scale for a design drawn under marginals: SALib reads only the direction of each step from
    ``x``, which a quantile function keeps), so
    the statistics are in each QoI's unit and the variance in its square: units per element ``qoi_units`` and
    ``qoi_units_squared``, which the caller attaches (:func:`.qois.qoi_coords`)."""
    from SALib.analyze import morris as morris_analyze

    x = np.asarray(x, dtype=float)
    y = np.asarray(y, dtype=float)
    if y.ndim == 1:
        y = y[:, None]
    d = len(names)
    if x.shape[1:] != (d,) or y.shape[0] != x.shape[0] or x.shape[0] % (d + 1) or x.shape[0] < 2 * (d + 1):
        raise ParameterError(f"Morris analysis: expected r >= 2 trajectories of d + 1 = {d + 1} rows, got x of shape "
                             f"{x.shape} and y of shape {y.shape}")
    if not np.isfinite(y).all():
        raise ParameterError("Morris analysis: model evaluations must be finite")
    rng = np.random.default_rng(seed)
    out = {k: np.zeros((y.shape[1], d)) for k in _KEYS}
    problem = salib_problem(names, lower, upper)
    constant = is_constant(y)
    for q in np.flatnonzero(~constant):
        res = morris_analyze.analyze(problem, x, y[:, q], num_resamples=resamples, conf_level=conf_level,
                                     num_levels=levels, seed=rng)
        for k in _KEYS:
            out[k][q] = np.asarray(res[k], dtype=float)
    data = {k: (("qoi", "param"), out[k], {UNITS_VARIABLE: "qoi_units"}) for k in _KEYS}
    data["variance"] = ("qoi", np.var(y, axis=0), {UNITS_VARIABLE: "qoi_units_squared"})
    return xr.Dataset(data, coords={"qoi": np.arange(y.shape[1]), "param": list(names)},
                      attrs={"conf_level": conf_level, "resamples": resamples, "levels": levels,
                             "trajectories": x.shape[0] // (d + 1)})
