"""The calibrated base model a diagnosis starts from: its own least-squares fit, or given parameter sets.

Two sources, one result (a :class:`~spflow.plugins.gap.least_squares.Fit` on the calibration data):

* **own fit** — weighted least squares on the simulator (:func:`~spflow.plugins.gap.least_squares.fit`) from the
  forward model's defaults (the thesis's calibrated Table 2.4 set, clipped into the ranges) plus ``starts - 1``
  Latin-hypercube points (``scipy.stats.qmc``, seeded);
* **given parameter sets** — the members of an upstream calibration (a Pareto set or posterior sample: a Dataset
  with ``values`` on dims (sample, param), param labels = the base model's parameter labels or the first UTCHEM
  name of each), in physical units. Every member (thinned to at most ``max_members``) is evaluated on the
  calibration data; the best (smallest whitened chi^2) is the start of a least-squares polish (``polish=True``)
  or, with ``polish=False``, the calibrated point itself (then only its Jacobian is computed).
"""

from __future__ import annotations

import numpy as np
import xarray as xr
from scipy.stats import qmc

from spflow.core.errors import ParameterError
from spflow.plugins.design.parameter_map import ParameterMap

from .layout import Layout
from .least_squares import Fit, WhitenedProblem, fit
from .prediction import Predictor

__all__ = ["calibrate_base", "parameter_set_starts"]


def parameter_set_starts(base, sets: xr.Dataset, max_members: int = 32) -> np.ndarray:
    """Unit-box points (m, p) of the members of ``sets`` (dims sample, param; variable ``values``): each member's
    forward-model values through the parameter map the sets carry (a design, an NSGA-II Pareto set or posterior draws
    of grouped or log-scale columns, :mod:`spflow.plugins.design.parameter_map`); a column named by a base-model label
    without a map is that parameter's value."""
    if "values" not in sets or tuple(sets["values"].dims) != ("sample", "param"):
        raise ParameterError("calibrated parameter sets need a variable 'values' on dims ('sample', 'param')")
    labels = [str(x) for x in sets["param"].values]
    rows = np.asarray(sets["values"].values, dtype=float)
    if not np.all(np.isfinite(rows)):
        raise ParameterError("calibrated parameter sets contain NaN or inf values")
    mapping = ParameterMap.of(sets)
    physical = [dict(zip(labels, map(float, row))) | mapping.forward_params(row) for row in rows]
    missing = [p.label for p in base.parameters if p.names[0] not in physical[0] and p.label not in physical[0]]
    if missing:
        raise ParameterError(f"calibrated parameter sets lack parameter {missing[0]!r} (have {labels})")
    values = np.array([[row[p.names[0]] if p.names[0] in row else row[p.label] for p in base.parameters]
                       for row in physical])
    step = max(1, int(np.ceil(values.shape[0] / max_members)))
    return base.unit(values[::step])


def calibrate_base(predictor: Predictor, layout: Layout, *, starts: int = 1, seed: int = 0, max_nfev: int = 30,
                   diff_step: float = 0.01, parameter_sets: np.ndarray | None = None, polish: bool = True,
                   economy: bool = True, first_round: str = "difference") -> Fit:
    """The calibrated base model on ``layout`` (module docstring); ``economy`` and ``first_round`` (with several
    starts): see :func:`~spflow.plugins.gap.least_squares.fit`."""
    base = predictor.base
    if parameter_sets is not None:
        problem = WhitenedProblem(predictor, layout, (), len(base.parameters), diff_step)
        members = list(np.atleast_2d(parameter_sets))
        chi2 = [float(r @ r) for r in problem.residuals(members)]
        best = members[int(np.argmin(chi2))]
        if polish:
            return fit(predictor, layout, [best], max_nfev=max_nfev, diff_step=diff_step)
        return Fit(best, (), len(best), problem.fun(best), problem.jac(best), 0, "given parameter set", best)
    points = [base.default_unit()]
    if starts > 1:
        points += list(qmc.LatinHypercube(d=len(base.parameters), seed=seed).random(starts - 1))
    return fit(predictor, layout, points, max_nfev=max_nfev, diff_step=diff_step, economy=economy,
               first_round=first_round)
