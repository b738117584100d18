"""The numbers behind the surrogate chapter's figures (thesis §3.5-3.8), as Datasets drawn by :mod:`.figures`.

Each function takes the Datasets of the registered stages -- a surrogate (``pce``, ``adaptive_pce``, ``pck``, ``gp``
or any kind loadable by :func:`~.contract.load_surrogate`), a validation ``design`` and the ``forward`` stage's
``responses`` at it -- and returns what a figure plots, with units, so a report can tabulate the same numbers:

* :func:`scatter_data` -- proxy vs simulator at the validation points (Figs. 3.4-3.5) with R² and the relative L2
  error (Eq. 3.15) pooled over PV, and R² of max over PV and of the final value (the stage ``surrogate_validation``'s
  ``r2_max``/``r2_final``, same helpers);
* :func:`moment_data` -- the proxy's mean and standard deviation over PV (Eqs. 3.11-3.12 from the PCE coefficients;
  for kinds without analytic moments the sample moments of the predicted mean at the validation points, as
  ``surrogate_validation`` does) against the sample moments of the runs (Eqs. 3.13-3.14) (Figs. 3.7-3.9);
* :func:`band_data` -- predicted mean ± σ of a few validation points and the fraction of all validation values inside
  mean ± 2σ (Fig. 3.15);
* :func:`error_history` -- ε_LOO^mean and ε_emp^mean (Eqs. 3.9-3.10) against the design size N_s (Fig. 3.3), from
  the ``adaptive_pce`` output's history or from fits on growing designs.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import xarray as xr

from spflow.core.errors import ParameterError

from .contract import Surrogate, load_surrogate
from .training_data import design_points
from .validation import matching_columns, r_squared, relative_l2

__all__ = ["scatter_data", "moment_data", "band_data", "error_history", "two_sigma_coverage", "POOLED"]

#: The ``variable`` label of the ``adaptive_pce`` history, which averages over all outputs.
POOLED = "all outputs"


def two_sigma_coverage(truth: np.ndarray, mean: np.ndarray, variance: np.ndarray) -> float:
    """Fraction of ``truth`` inside ``mean`` ± 2σ (σ² = ``variance``), with a round-off allowance of 1e-12 max|y|."""
    inside = np.abs(mean - truth) <= 2.0 * np.sqrt(variance) + 1e-12 * np.abs(truth).max()
    return float(inside.mean())


def _columns(model: Surrogate, variables: Sequence[str], experiment: str) -> dict[str, np.ndarray]:
    """Output columns (increasing PV) of each variable; unknown names raise before any prediction."""
    variables = list(variables)
    if not variables or len(set(variables)) != len(variables):
        raise ParameterError(f"surrogate figures: 'variables' must be a non-empty list without repeats, got "
                             f"{variables!r}")
    return {v: model.outputs.columns(v, experiment) for v in variables}


def _validation(model: Surrogate, design: xr.Dataset, responses: xr.Dataset, variables: Sequence[str],
                experiment: str) -> tuple[dict[str, np.ndarray], np.ndarray, np.ndarray]:
    """(columns per variable, points x (N, d), simulator values (N, n_output) in the model's output order)."""
    cols = _columns(model, variables, experiment)
    x = design_points(design, model.names, model.lower, model.upper)
    if responses.sizes.get("sample") != x.shape[0]:
        raise ParameterError(f"surrogate figures: the responses have {responses.sizes.get('sample')} samples, the "
                             f"design {x.shape[0]} points")
    return cols, x, matching_columns(responses, model.outputs)


def _series(name: str, values: np.ndarray, pv: np.ndarray, unit: str, dims: tuple[str, ...], **coords) -> xr.Dataset:
    """One (…, pv) array as a Dataset, so variables on different PV grids merge by outer join."""
    pv_coord = ("pv", pv, {"units": "1", "long_name": "injected pore volumes"})
    return xr.Dataset({name: (dims, values, {"units": unit})}, coords={"pv": pv_coord, **coords})


def scatter_data(surrogate: xr.Dataset, design: xr.Dataset, responses: xr.Dataset, *,
                 variables: Sequence[str] = ("dp", "recovery"), experiment: str = "BCF1") -> xr.Dataset:
    """Simulator (``<variable>_simulator``) and proxy mean (``<variable>_proxy``), dims (sample, pv), at the points
    of ``design``, and per variable: ``r2_pooled`` and ``l2_pooled`` (Eq. 3.15) over all (sample, PV) values,
    ``r2_max`` (of the maximum over PV) and ``r2_final`` (of the last PV step)."""
    model = load_surrogate(surrogate)
    cols, x, truth = _validation(model, design, responses, variables, experiment)
    predicted, _ = model.predict(x)
    samples = np.asarray(design["sample"].values)
    parts, stats = [], {k: [] for k in ("r2_pooled", "l2_pooled", "r2_max", "r2_final")}
    for v, c in cols.items():
        y, mu = truth[:, c], predicted[:, c]
        for suffix, values in (("simulator", y), ("proxy", mu)):
            parts.append(_series(f"{v}_{suffix}", values, model.outputs.pv[c], model.outputs.units[v],
                                 ("sample", "pv"), sample=samples))
        stats["r2_pooled"].append(float(r_squared(y.ravel(), mu.ravel())))
        stats["l2_pooled"].append(relative_l2(y, mu))
        stats["r2_max"].append(float(r_squared(y.max(axis=1), mu.max(axis=1))))
        stats["r2_final"].append(float(r_squared(y[:, -1], mu[:, -1])))
    ds = xr.merge(parts, join="outer")
    for k, values in stats.items():
        ds[k] = ("variable", np.array(values), {"units": "1"})
    ds = ds.assign_coords(variable=list(cols))
    ds.attrs = {"surrogate": surrogate.attrs["surrogate"], "experiment": experiment, "n_validation": x.shape[0]}
    return ds


def moment_data(surrogate: xr.Dataset, responses: xr.Dataset, *, design: xr.Dataset | None = None,
                variables: Sequence[str] = ("dp", "recovery"), experiment: str = "BCF1") -> xr.Dataset:
    """Per variable, over PV: the proxy's ``<variable>_proxy_mean``/``_proxy_std`` and the runs' sample
    ``<variable>_sample_mean``/``_sample_std`` (population std, Eqs. 3.13-3.14), with the relative L2 errors
    (Eq. 3.15) ``mean_l2_error`` and ``variance_l2_error`` per variable.

    The proxy's moments are its analytic ``moments()`` when the kind has them (PCE: Eqs. 3.11-3.12, read off the
    coefficients); otherwise the mean and std of its predicted mean at the points of ``design`` (then required), the
    responses being the runs at those points. ``attrs["moments"]`` says which.
    """
    model = load_surrogate(surrogate)
    analytic = getattr(model, "moments", None)
    if analytic is None and design is None:
        raise ParameterError(f"surrogate figures: a {model.kind!r} surrogate has no analytic moments; pass the "
                             f"validation 'design' (the points of 'responses') to use its predictions there")
    if design is None:
        cols = _columns(model, variables, experiment)
        truth = matching_columns(responses, model.outputs)
    else:
        cols, x, truth = _validation(model, design, responses, variables, experiment)
    if analytic is not None:
        mean, var = analytic()
        how = "analytic (Eqs. 3.11-3.12, from the coefficients)"
    else:
        predicted, _ = model.predict(x)
        mean, var = predicted.mean(axis=0), predicted.var(axis=0)
        how = f"sample moments of the predicted mean at the {x.shape[0]} validation points"
    parts, l2 = [], {"mean_l2_error": [], "variance_l2_error": []}
    for v, c in cols.items():
        unit, pv = model.outputs.units[v], model.outputs.pv[c]
        sample_mean, sample_var = truth[:, c].mean(axis=0), truth[:, c].var(axis=0)
        for name, values in (("proxy_mean", mean[c]), ("proxy_std", np.sqrt(var[c])), ("sample_mean", sample_mean),
                             ("sample_std", np.sqrt(sample_var))):
            parts.append(_series(f"{v}_{name}", values, pv, unit, ("pv",)))
        l2["mean_l2_error"].append(relative_l2(sample_mean, mean[c]))
        l2["variance_l2_error"].append(relative_l2(sample_var, var[c]))
    ds = xr.merge(parts, join="outer")
    for k, values in l2.items():
        ds[k] = ("variable", np.array(values), {"units": "1"})
    ds = ds.assign_coords(variable=list(cols))
    ds.attrs = {"surrogate": surrogate.attrs["surrogate"], "experiment": experiment, "moments": how,
                "n_runs": truth.shape[0]}
    return ds


def band_data(surrogate: xr.Dataset, design: xr.Dataset, responses: xr.Dataset, *, n_show: int = 3,
              reference: xr.Dataset | None = None, variables: Sequence[str] = ("dp", "recovery"),
              experiment: str = "BCF1") -> xr.Dataset:
    """For the first ``n_show`` points of ``design``: the proxy's ``<variable>_mean`` and ``<variable>_std``
    (square root of the predicted variance), the runs' ``<variable>_simulator`` and, with a ``reference`` surrogate
    (e.g. the PCE next to PC-Kriging), its ``<variable>_reference_mean``; dims (sample, pv). Per variable,
    ``coverage``: the fraction of all validation values (every point and PV step) inside mean ± 2σ."""
    model = load_surrogate(surrogate)
    cols, x, truth = _validation(model, design, responses, variables, experiment)
    if isinstance(n_show, bool) or not isinstance(n_show, (int, np.integer)) or not 1 <= n_show <= x.shape[0]:
        raise ParameterError(f"surrogate figures: n_show must be an integer in [1, {x.shape[0]}] (the validation "
                             f"points), got {n_show!r}")
    ref = load_surrogate(reference) if reference is not None else None
    ref_cols = _columns(ref, variables, experiment) if ref is not None else {}
    for v, c in ref_cols.items():
        pv, own = ref.outputs.pv[c], model.outputs.pv[cols[v]]
        if pv.shape != own.shape or not np.allclose(pv, own, rtol=0, atol=1e-9):
            raise ParameterError(f"surrogate figures: the reference surrogate's {v!r} PV grid differs from the "
                                 f"surrogate's")
    mean, var = model.predict(x)
    if ref is not None:
        ref_mean = ref.predict(design_points(design, ref.names, ref.lower, ref.upper)[:n_show])[0]
    samples = np.asarray(design["sample"].values)[:n_show]
    parts, coverage = [], []
    for v, c in cols.items():
        unit, pv = model.outputs.units[v], model.outputs.pv[c]
        series = {"mean": mean[:n_show, c], "std": np.sqrt(var[:n_show, c]), "simulator": truth[:n_show, c]}
        if ref is not None:
            series["reference_mean"] = ref_mean[:, ref_cols[v]]
        for name, values in series.items():
            parts.append(_series(f"{v}_{name}", values, pv, unit, ("sample", "pv"), sample=samples))
        coverage.append(two_sigma_coverage(truth[:, c], mean[:, c], var[:, c]))
    ds = xr.merge(parts, join="outer")
    ds["coverage"] = ("variable", np.array(coverage), {"units": "1", "long_name": "fraction inside mean ± 2σ"})
    ds = ds.assign_coords(variable=list(cols))
    ds.attrs = {"surrogate": surrogate.attrs["surrogate"], "experiment": experiment, "n_validation": x.shape[0],
                "reference": reference.attrs["surrogate"] if reference is not None else ""}
    return ds


def _fit_errors(fit: xr.Dataset) -> tuple[int, dict[str, tuple[float, float]], float]:
    """(N_s, {variable: (mean LOO, mean empirical error)}, degree) of one stored fit."""
    if "loo" not in fit or ("n_train" not in fit.attrs and "train" not in fit.dims):
        raise ParameterError(f"surrogate figures: a {fit.attrs.get('surrogate')!r} fit without per-output 'loo' "
                             f"errors and training size cannot enter an error history")
    n = int(fit.attrs["n_train"]) if "n_train" in fit.attrs else fit.sizes["train"]
    variables = fit["output_variable"].values.astype(str)
    empirical = fit["empirical"].values if "empirical" in fit else np.full(variables.size, np.nan)
    errors = {str(v): (float(fit["loo"].values[variables == v].mean()), float(empirical[variables == v].mean()))
              for v in dict.fromkeys(variables)}
    return n, errors, float(fit.attrs.get("degree", fit.attrs.get("pce_degree", np.nan)))


def error_history(fits: xr.Dataset | Sequence[xr.Dataset]) -> xr.Dataset:
    """ε_LOO^mean (``loo``) and ε_emp^mean (``empirical``), dims (n_s, variable), and the selected ``degree`` (n_s).

    ``fits`` is either the ``adaptive_pce`` stage's output -- its history averages over all outputs, so ``variable``
    is :data:`POOLED` -- or surrogate Datasets fitted on growing designs (any order; sorted by N_s), whose stored
    per-output errors are averaged per variable (Eq. 3.9 per QoI). Kriging fits have no ε_emp (NaN). A history
    (this function's output) is returned unchanged.
    """
    if isinstance(fits, xr.Dataset) and fits.get("loo") is not None and fits["loo"].dims == ("n_s", "variable"):
        return fits  # already a history
    if isinstance(fits, xr.Dataset):
        if "loo_history" not in fits:
            raise ParameterError("surrogate figures: a single Dataset must be an 'adaptive_pce' output (with "
                                 "'loo_history'); pass fits on growing designs as a list")
        n_s = fits["n_s"].values
        loo, emp = fits["loo_history"].values[:, None], fits["empirical_history"].values[:, None]
        degree = fits["degree_history"].values.astype(float)
        variables = [POOLED]
    else:
        rows = sorted((_fit_errors(f) for f in fits), key=lambda r: r[0])
        if not rows:
            raise ParameterError("surrogate figures: error_history needs at least one fit")
        variables = list(rows[0][1])
        if any(list(r[1]) != variables for r in rows):
            raise ParameterError(f"surrogate figures: the fits must all approximate the variables {variables}")
        n_s = np.array([r[0] for r in rows])
        loo = np.array([[r[1][v][0] for v in variables] for r in rows])
        emp = np.array([[r[1][v][1] for v in variables] for r in rows])
        degree = np.array([r[2] for r in rows])
    return xr.Dataset(
        {"loo": (("n_s", "variable"), loo, {"units": "1", "long_name": "mean LOO error ε_LOO^mean (Eq. 3.9)"}),
         "empirical": (("n_s", "variable"), emp, {"units": "1", "long_name": "mean empirical error (Eq. 3.10)"}),
         "degree": ("n_s", degree, {"units": "1", "long_name": "selected total degree p"})},
        coords={"n_s": ("n_s", n_s, {"units": "1", "long_name": "training design size N_s"}), "variable": variables})
