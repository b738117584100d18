"""Sobol' indices with SALib: the Saltelli cross-sampled design on Sobol' points and the first-order (Eq. 3.2) and
total (Eq. 3.3) index estimators with bootstrap confidence intervals.

``sobol_sample`` wraps :func:`SALib.sample.sobol.sample` (not the deprecated ``saltelli``) and
``sobol_indices`` wraps :func:`SALib.analyze.sobol.analyze` for a matrix of model evaluations (one column per QoI),
returning an xarray Dataset over (``qoi``, ``param``). SALib's estimators are those of Saltelli et al. (2010):
S_i from mean(f_B (f_ABi - f_A)) and S_i^T from Jansen's mean((f_A - f_ABi)^2)/2, both over the variance of [f_A, f_B].

A QoI that does not vary over the design gets zero indices (:mod:`.salib_glue`).
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from spflow.core.cf_metadata import UNITS_VARIABLE
from spflow.core.errors import ParameterError

from .salib_glue import is_constant, salib_design, salib_problem

__all__ = ["check_base_samples", "sobol_runs", "sobol_sample", "sobol_indices"]


def check_base_samples(samples: int, where: str = "Sobol' base sample size N") -> None:
    """Raise :class:`ParameterError` unless ``samples`` is a power of two: the balance of Sobol' points (and the
    estimators' error) relies on it."""
    if samples < 1 or samples & (samples - 1):
        low = 1 << max(samples.bit_length() - 1, 0)
        raise ParameterError(f"{where} = {samples!r} must be a power of two (1, 2, 4, ..., e.g. {low} or {2 * low})")


def sobol_runs(samples: int, d: int, calc_second_order: bool) -> int:
    """Model runs of a Saltelli design: N (d + 2), or N (2 d + 2) with second-order indices."""
    return samples * (2 * d + 2 if calc_second_order else d + 2)


def sobol_sample(names: list[str], lower: np.ndarray, upper: np.ndarray, samples: int, *,
                 calc_second_order: bool = False, seed: int | np.random.Generator | None = None,
                 inputs=None) -> np.ndarray:
    """The (``sobol_runs``, d) Saltelli design on the box ``lower``..``upper`` (physical units), in SALib's row order;
    ``samples`` (N) must be a power of two. With ``inputs`` (one marginal per name,
    :mod:`spflow.plugins.surrogates.input_marginals`) the design is drawn from the marginals (:mod:`.salib_glue`), so
    :func:`sobol_indices` of its evaluations are the indices under them."""
    from SALib.sample import sobol as sobol_sampler  # SALib loads when a design is drawn

    check_base_samples(samples)
    return salib_design(lambda problem: sobol_sampler.sample(problem, samples, calc_second_order=calc_second_order,
                                                             scramble=True, seed=seed), names, lower, upper, inputs)


def sobol_indices(y: np.ndarray, names: list[str], *, calc_second_order: bool = False, conf_level: float = 0.95,
                  resamples: int = 100, seed: int | np.random.Generator | None = None) -> xr.Dataset:
    """S1, S1_conf, ST, ST_conf (dims ``qoi``, ``param``; dimensionless) and the QoI ``variance`` (``qoi``) from the
    evaluations ``y`` (n_runs, n_qoi) of a :func:`sobol_sample` design over ``names`` (rows in the sampler's order).

    With ``calc_second_order`` also S2, S2_conf (``qoi``, ``param``, ``param_j``; NaN on and below the diagonal).
    ``*_conf`` are half-widths of the ``conf_level`` bootstrap interval over ``resamples`` resamples.
    """
    from SALib.analyze import sobol as sobol_analyze

    y = np.asarray(y, dtype=float)
    if y.ndim == 1:
        y = y[:, None]
    d = len(names)
    per_base = sobol_runs(1, d, calc_second_order)
    if y.ndim != 2 or y.shape[0] == 0 or y.shape[0] % per_base:
        form = "N (2 d + 2)" if calc_second_order else "N (d + 2)"
        raise ParameterError(f"Sobol' analysis: expected a multiple of {per_base} rows ({form} for d = {d}), got an "
                             f"array of shape {y.shape}")
    if not np.isfinite(y).all():
        raise ParameterError("Sobol' analysis: model evaluations must be finite")
    rng = np.random.default_rng(seed)
    keys = ["S1", "S1_conf", "ST", "ST_conf"] + (["S2", "S2_conf"] if calc_second_order else [])
    out = {k: np.zeros((y.shape[1], d, d) if k.startswith("S2") else (y.shape[1], d)) for k in keys}
    constant = is_constant(y)
    problem = salib_problem(names, np.zeros(d), np.ones(d))
    for q in range(y.shape[1]):
        if constant[q]:
            if calc_second_order:
                out["S2"][q] = out["S2_conf"][q] = np.where(np.triu(np.ones((d, d), bool), 1), 0.0, np.nan)
            continue
        res = sobol_analyze.analyze(problem, y[:, q], calc_second_order=calc_second_order,
                                    num_resamples=resamples, conf_level=conf_level, seed=rng)
        for k in keys:
            out[k][q] = res[k]
    variance = np.var(y, axis=0)
    data = {k: (("qoi", "param"), out[k], {"units": "1"}) for k in ("S1", "S1_conf", "ST", "ST_conf")}
    if calc_second_order:
        data |= {k: (("qoi", "param", "param_j"), out[k], {"units": "1"}) for k in ("S2", "S2_conf")}
    data["variance"] = ("qoi", variance, {UNITS_VARIABLE: "qoi_units_squared"})  # the caller attaches the units
    coords = {"qoi": np.arange(y.shape[1]), "param": list(names)}
    if calc_second_order:
        coords["param_j"] = list(names)
    return xr.Dataset(data, coords=coords, attrs={"conf_level": conf_level, "resamples": resamples,
                                                   "base_samples": y.shape[0] // per_base})
