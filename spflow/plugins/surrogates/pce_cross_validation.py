"""K-fold cross-validation of the whole degree-adaptive PCE fit: an error estimate that has not seen its own selection.

The corrected LOO of the selected model (thesis Eq. 3.8 with the factor T(P, N) of Chapelle, Vapnik & Bengio 2002,
:mod:`.regression`) scores a model whose LARS support, degree and q were chosen by minimising that same estimate over
every candidate, with every point taking part in the choice: a selected model's LOO is biased low (Varma & Simon 2006,
BMC Bioinformatics 7:91; Cawley & Talbot 2010, J. Mach. Learn. Res. 11:2079). The unbiased remedy they give is to
cross-validate the whole procedure ("nested" cross-validation): the N points are split into K folds; for each fold the
whole fit of :func:`.degree_adaptive.fit_pce` (degree and q search, LARS ranking, choice of the prefix, OLS refit), with
the options of the final fit, runs on the other K − 1 folds and predicts the held-out points; those fold models are
thrown away. Per output,

    ε_CV = (1/N) Σ_i (y_i − ŷ_{−k(i)}(z_i))² / Var̂(y),

Var̂ the population variance of the N training outputs (the normalisation of Eqs. 3.7-3.8), 0 for a constant output
(:func:`.regression.is_constant`). The final model is the one fitted on all N points; ε_CV estimates the error of the
fitting procedure at (K − 1)N/K points, so it errs high wherever the error still falls fast with N (measured in
docs/surrogates.md, "The reported error").

Folds: :func:`.folds.fold_indices`. Cost: K fits on (K − 1)N/K points, about K times the fit.
"""

from __future__ import annotations

import math
import warnings

import numpy as np

from spflow.core.errors import DegreeCapWarning, ParameterError

from .degree_adaptive import fit_pce
from .folds import fold_indices
from .regression import is_constant

__all__ = ["check_folds", "kfold_error"]


def check_folds(folds, n: int, d: int, solver: str, where: str) -> None:
    """``folds`` must be 0 (no cross-validation) or an integer in [2, n] leaving every fold's fit enough points: at
    least 3, and for ``solver`` "ols" more than the d + 1 terms of the degree-1 basis. ``where`` names the caller."""
    if isinstance(folds, bool) or not isinstance(folds, (int, np.integer)) or folds < 0 or folds == 1:
        raise ParameterError(f"{where}: cv_folds must be 0 (report the corrected LOO) or an integer >= 2 (K-fold "
                             f"cross-validation of the whole fit), got {folds!r}")
    if folds == 0:
        return
    if folds > n:
        raise ParameterError(f"{where}: cv_folds = {folds} exceeds the N = {n} training runs (at most one fold per "
                             f"run)")
    train = n - math.ceil(n / folds)
    need = max(3, d + 2) if solver == "ols" else 3
    if train < need:
        raise ParameterError(f"{where}: cv_folds = {folds} leaves {train} of the N = {n} training runs to a fold's "
                             f"fit; it needs at least {need} (solver {solver!r}, {d} inputs): use fewer folds or more "
                             f"runs")


def kfold_error(z: np.ndarray, y: np.ndarray, folds: int, **options) -> np.ndarray:
    """ε_CV (m,) of the fit ``fit_pce(z, y, **options)`` (``z`` (N, d) reference points, ``y`` (N, m)) by
    ``folds``-fold cross-validation of the whole fit (module docstring). The fold fits' degree-cap warnings are not
    passed on (their models are thrown away); ``options`` must not hold ``progress``."""
    from .basis import design_matrix  # numba: loaded when a PCE is fitted

    residuals = np.empty_like(y)
    everything = np.arange(y.shape[0])
    for held in fold_indices(y.shape[0], folds):
        train = np.setdiff1d(everything, held)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", DegreeCapWarning)
            fit = fit_pce(z[train], y[train], **options)
        psi = design_matrix(z[held], fit.indices, options.get("families"))
        residuals[held] = psi @ fit.coefficients.T - y[held]
    with np.errstate(divide="ignore", invalid="ignore"):
        error = np.mean(residuals**2, axis=0) / y.var(axis=0)
    return np.where(is_constant(y), 0.0, error)
