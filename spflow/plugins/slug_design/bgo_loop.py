"""Bayesian global optimisation of two noisy, minimised objectives with EEIHV (thesis §4.7, Figs. 4.7-4.8).

The loop of Pandita et al. (2018, thesis ref. [214]; docs/eeihv.md §5), with both objectives minimised:

1. evaluate ``n_init`` Latin-hypercube designs (one noisy realisation each);
2. fit one GP per objective (:class:`.objective_models.ObjectiveGP`, learned noise);
3. project: Ŷ = GP means at the observed designs; the *projected front* is the non-dominated subset of Ŷ, and the
   reference point r follows :func:`.pareto_front.reference_point` unless the caller fixes it;
4. maximise EEIHV (:mod:`.eeihv`) over the design box: the closed form on ``n_candidates`` Latin-hypercube
   candidates at once, then L-BFGS-B with the analytic gradient from the ``n_polish`` best candidates;
5. stop when rel = max EEIHV / (max EEIHV of the first iteration) < ``rtol`` once ``min_iter`` iterations are done,
   or after ``max_iter`` iterations; otherwise evaluate the chosen design(s), append, and go to 2.

Batch mode (``batch`` = q > 1) picks q designs per iteration greedily by the *Kriging believer*: after each pick the
GPs are conditioned (hyperparameters kept) on a fantasised observation equal to their own mean at the pick, which
shrinks the predictive variance there, the projection, front and r are recomputed, and EEIHV is maximised again.
pydes draws the fantasy from the predictive distribution instead; the believer is deterministic.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

import numpy as np
import xarray as xr
from scipy.optimize import minimize
from scipy.stats import qmc

from spflow.core.cf_metadata import UNITS_VARIABLE, squared_unit
from spflow.core.errors import ParameterError

from .eeihv import eeihv, eeihv_and_gradient
from .objective_models import GP_KERNELS, ObjectiveGP
from .pareto_front import nondominated, reference_point

__all__ = ["BGOResult", "design_eeihv", "run_bgo"]


@dataclass
class BGOResult:
    """State of an EEIHV run (both objectives minimised).

    ``X`` (n, d) designs in physical units, ``Y`` (n, 2) their noisy observations, ``iteration`` (n,) the iteration
    that chose each design (0: initial design), ``eeihv_max`` (iterations,) the maximum EEIHV found at each
    iteration (in objective-1 × objective-2 units), ``projected`` and ``projected_std`` (n, 2) the latent GP mean and
    standard deviation at ``X``, ``front_index`` the rows of the projected Pareto front (ascending in objective 1),
    ``reference`` (2,) the hypervolume reference point, ``hyperparameters`` one dict per objective
    (:meth:`.ObjectiveGP.hyperparameters`), ``stop_reason`` ``"rtol"``, ``"max_iter"`` or ``"running"``, and
    ``models`` the two fitted GPs (for :func:`.front_uncertainty.front_uncertainty`).
    """

    X: np.ndarray
    Y: np.ndarray
    iteration: np.ndarray
    eeihv_max: np.ndarray
    projected: np.ndarray
    projected_std: np.ndarray
    front_index: np.ndarray
    reference: np.ndarray
    hyperparameters: list[dict]
    bounds: np.ndarray
    stop_reason: str
    models: tuple[ObjectiveGP, ObjectiveGP] = field(repr=False)

    @property
    def front(self) -> np.ndarray:
        """Projected Pareto front (k, 2)."""
        return self.projected[self.front_index]

    def to_dataset(self, design_names=None, design_units=None, objective_names=("objective_1", "objective_2"),
                   objective_units=("", "")) -> xr.Dataset:
        """The run as a Dataset with dims (evaluation, design_var, objective, iteration).

        Per-coordinate units are the coordinates ``design_units``, ``objective_units`` and
        ``objective_units_squared`` (UDUNITS strings, or whatever the caller gives); a variable in them has units per
        element (``attrs["units_variable"]`` names the coordinate, :mod:`spflow.core.cf_metadata`).
        """
        n, d = self.X.shape
        design_names = [f"x{j}" for j in range(d)] if design_names is None else list(design_names)
        design_units = [""] * d if design_units is None else list(design_units)
        if len(design_names) != d or len(design_units) != d:
            raise ParameterError(f"to_dataset: design_names and design_units need {d} entries each")
        if len(objective_names) != 2 or len(objective_units) != 2:
            raise ParameterError("to_dataset: objective_names and objective_units need 2 entries each")
        per_design = {UNITS_VARIABLE: "design_units"}
        per_objective = {UNITS_VARIABLE: "objective_units"}
        squared = {UNITS_VARIABLE: "objective_units_squared"}
        hyper = {key: np.array([h[key] for h in self.hyperparameters]) for key in self.hyperparameters[0]}
        on_front = np.zeros(n, dtype=bool)
        on_front[self.front_index] = True
        eeihv_units = f"({objective_units[0]})*({objective_units[1]})"
        return xr.Dataset(
            {
                "design": (("evaluation", "design_var"), self.X, per_design),
                "observed": (("evaluation", "objective"), self.Y,
                             {**per_objective, "description": "one noisy realisation per design"}),
                "projected": (("evaluation", "objective"), self.projected,
                              {**per_objective, "description": "latent GP posterior mean at the design"}),
                "projected_std": (("evaluation", "objective"), self.projected_std, per_objective),
                "chosen_at": (("evaluation",), self.iteration,
                              {"units": "1", "description": "BGO iteration that chose the design (0: initial LHS)"}),
                "on_front": (("evaluation",), on_front, {"units": "1", "description": "on the projected front"}),
                "eeihv_max": (("iteration",), self.eeihv_max, {"units": eeihv_units}),
                "reference": (("objective",), self.reference, per_objective),
                "lengthscale": (("objective", "design_var"), hyper["lengthscale"], per_design),
                "signal_variance": (("objective",), hyper["signal_variance"], squared),
                "noise_variance": (("objective",), hyper["noise_variance"], squared),
                "lower": (("design_var",), self.bounds[:, 0], per_design),
                "upper": (("design_var",), self.bounds[:, 1], per_design),
            },
            coords={"evaluation": ("evaluation", np.arange(n), {"units": "1", "long_name": "evaluation number"}),
                    "design_var": design_names, "objective": list(objective_names),
                    "iteration": ("iteration", np.arange(1, self.eeihv_max.size + 1),
                                  {"units": "1", "long_name": "BGO iteration"}),
                    "design_units": ("design_var", design_units, {"long_name": "unit of each design variable"}),
                    "objective_units": ("objective", list(objective_units), {"long_name": "unit of each objective"}),
                    "objective_units_squared": ("objective", [squared_unit(u) for u in objective_units],
                                                {"long_name": "unit of each objective squared"})},
            attrs={"method": "Bayesian global optimisation with EEIHV (thesis §4.7)",
                   "convention": "both objectives minimised", "stop_reason": self.stop_reason},
        )


def _check_inputs(bounds, n_init, max_iter, rtol, min_iter, batch, n_candidates, n_polish, gp_restarts, kernel,
                  reference, reference_margin) -> tuple[np.ndarray, np.ndarray | None]:
    bounds = np.asarray(bounds, dtype=float)
    if bounds.ndim != 2 or bounds.shape[1] != 2 or bounds.shape[0] < 1:
        raise ParameterError(f"run_bgo: bounds must have shape (d, 2) (lower, upper per design variable), "
                             f"got {bounds.shape}")
    if not np.isfinite(bounds).all() or (bounds[:, 1] <= bounds[:, 0]).any():
        raise ParameterError(f"run_bgo: bounds must be finite with lower < upper, got {bounds.tolist()}")
    for name, value, low in [("n_init", n_init, 2), ("max_iter", max_iter, 0), ("min_iter", min_iter, 0),
                             ("batch", batch, 1), ("n_candidates", n_candidates, 1), ("n_polish", n_polish, 0),
                             ("gp_restarts", gp_restarts, 1)]:
        if not isinstance(value, (int, np.integer)) or isinstance(value, bool) or value < low:
            raise ParameterError(f"run_bgo: {name} must be an integer >= {low}, got {value!r}")
    if not (np.isfinite(rtol) and rtol >= 0):
        raise ParameterError(f"run_bgo: rtol must be a finite number >= 0, got {rtol!r}")
    if not (np.isfinite(reference_margin) and reference_margin >= 0):
        raise ParameterError(f"run_bgo: reference_margin must be a finite number >= 0, got {reference_margin!r}")
    if kernel not in GP_KERNELS:
        raise ParameterError(f"run_bgo: kernel {kernel!r} is not known; allowed: {sorted(GP_KERNELS)}")
    if reference is not None:
        reference = np.asarray(reference, dtype=float)
        if reference.shape != (2,) or not np.isfinite(reference).all():
            raise ParameterError(f"run_bgo: reference must be 2 finite numbers, got {reference}")
    return bounds, reference


def _evaluate(objective: Callable, x: np.ndarray) -> np.ndarray:
    y = np.asarray(objective(x), dtype=float)
    if y.shape != (x.shape[0], 2):
        raise ParameterError(f"run_bgo: objective must return shape ({x.shape[0]}, 2) for {x.shape[0]} designs, "
                             f"got {y.shape}")
    bad = ~np.isfinite(y).all(axis=1)
    if bad.any():
        raise ParameterError(f"run_bgo: objective returned non-finite values (Y) at design rows "
                             f"{np.flatnonzero(bad).tolist()}: {x[bad].tolist()}")
    return y


def _project(models, x) -> tuple[np.ndarray, np.ndarray]:
    stats = [m.predict(x) for m in models]
    return np.column_stack([s[0] for s in stats]), np.column_stack([s[1] for s in stats])


def design_eeihv(models, x: np.ndarray, front: np.ndarray,
                 reference: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """EEIHV (m,) of designs ``x`` (m, d) under the two GPs ``models`` and its gradient (m, d) with respect to x.

    Chain rule: ∂EEIHV/∂x = Σ_k ∂EEIHV/∂μ_k · ∂μ_k/∂x + ∂EEIHV/∂s_k · ∂s_k/∂x, the GP derivatives from
    :meth:`.ObjectiveGP.predict_with_gradient`.
    """
    stats = [m.predict_with_gradient(x) for m in models]
    value, d_mu, d_sd = eeihv_and_gradient(np.column_stack([s[0] for s in stats]),
                                           np.column_stack([s[1] for s in stats]), front, reference)
    grad = sum(d_mu[:, [k]] * stats[k][2] + d_sd[:, [k]] * stats[k][3] for k in range(2))
    return value, grad


def _maximise_eeihv(models, front, reference, bounds, n_candidates, n_polish, rng) -> tuple[np.ndarray, float]:
    """Design (d,) maximising EEIHV and the maximum: vectorised candidate search, then L-BFGS-B polishing."""
    lower, width = bounds[:, 0], bounds[:, 1] - bounds[:, 0]
    candidates = lower + width * qmc.LatinHypercube(d=bounds.shape[0], rng=rng).random(n_candidates)
    values = eeihv(*_project(models, candidates), front, reference)
    order = np.argsort(values)[::-1]
    best_x, best = candidates[order[0]], float(values[order[0]])
    if best <= 0.0:
        return best_x, best
    scale = best  # L-BFGS-B sees −EEIHV/scale on unit-cube coordinates u, so its tolerances are relative

    def negative(u):
        value, grad = design_eeihv(models, (lower + width * u)[None, :], front, reference)
        return -value[0] / scale, -grad[0] * width / scale

    for i in order[:n_polish]:
        res = minimize(negative, (candidates[i] - lower) / width, jac=True, method="L-BFGS-B",
                       bounds=[(0.0, 1.0)] * bounds.shape[0])
        if np.isfinite(res.fun) and -res.fun * scale > best:
            best_x, best = lower + width * np.clip(res.x, 0.0, 1.0), float(-res.fun * scale)
    return best_x, best


def run_bgo(objective: Callable[[np.ndarray], np.ndarray], bounds: np.ndarray, *, n_init: int = 20,
            max_iter: int = 100, rtol: float = 1e-2, min_iter: int = 10, batch: int = 1, seed: int = 0,
            n_candidates: int = 2000, n_polish: int = 5, gp_restarts: int = 3, kernel: str = "matern52",
            reference: np.ndarray | None = None, reference_margin: float = 0.1,
            callback: Callable[[BGOResult], None] | None = None) -> BGOResult:
    """Minimise two noisy objectives with EEIHV; see the module docstring for the loop.

    ``objective`` maps designs (q, d) in physical units to one noisy realisation (q, 2) of both (minimised)
    objectives; it is called once with the ``n_init`` initial designs and once per iteration with ``batch`` designs.
    ``reference`` fixes the hypervolume reference point; by default it is max + ``reference_margin``·range of the
    projected values, only ever moved outwards (pydes' rule; docs/eeihv.md §3). ``callback`` receives the partial
    :class:`BGOResult` after each GP refit (the initial design included) and the final result once more.
    """
    bounds, fixed_reference = _check_inputs(bounds, n_init, max_iter, rtol, min_iter, batch, n_candidates, n_polish,
                                            gp_restarts, kernel, reference, reference_margin)
    rng = np.random.default_rng(seed)
    lower, width = bounds[:, 0], bounds[:, 1] - bounds[:, 0]
    x = lower + width * qmc.LatinHypercube(d=bounds.shape[0], rng=rng).random(n_init)
    y = _evaluate(objective, x)
    chosen_at = np.zeros(n_init, dtype=int)
    history: list[float] = []
    ref = fixed_reference

    def fit(x, y, previous):
        return tuple(ObjectiveGP.fit(x, y[:, k], bounds, kernel=kernel, restarts=gp_restarts,
                                     seed=int(rng.integers(2**31)), start=previous and previous[k]) for k in range(2))

    def state(models, x, previous):
        projected, projected_std = _project(models, x)
        r = fixed_reference if fixed_reference is not None else reference_point(projected, reference_margin, previous)
        return projected, projected_std, nondominated(projected), r

    iteration, models = 0, None
    while True:
        models = fit(x, y, models)
        projected, projected_std, front_index, ref = state(models, x, ref)
        result = BGOResult(x, y, chosen_at, np.array(history), projected, projected_std, front_index, ref,
                           [m.hyperparameters() for m in models], bounds, "running", models)
        if iteration >= max_iter:
            result.stop_reason = "max_iter"
            break
        if callback is not None:
            callback(result)
        picks, pending_models, batch_ref = [], models, ref
        for _ in range(batch):
            if picks:  # Kriging believer: condition on the GP's own mean at the previous picks
                xp = np.array(picks)
                pending_models = tuple(m.conditioned_on(xp, m.predict(xp)[0]) for m in models)
                x_all = np.vstack([x, xp])
                projected_b, _, front_b, batch_ref = state(pending_models, x_all, batch_ref)
                front_values = projected_b[front_b]
            else:
                front_values = projected[front_index]
            x_new, value = _maximise_eeihv(pending_models, front_values, batch_ref, bounds, n_candidates, n_polish,
                                           rng)
            if not picks:
                history.append(value)
            picks.append(x_new)
        if iteration >= min_iter and history[0] > 0 and history[-1] / history[0] < rtol:
            result.eeihv_max, result.stop_reason = np.array(history), "rtol"
            break
        x_new = np.array(picks)
        x, y = np.vstack([x, x_new]), np.vstack([y, _evaluate(objective, x_new)])
        iteration += 1
        chosen_at = np.append(chosen_at, np.full(batch, iteration))
    if callback is not None:
        callback(result)
    return result
