"""The ``posterior_predictive`` stage: simulator runs on posterior draws, their quantile bands and the coverage of the
observations (thesis Figs. 4.4-4.5: the training coreflood BCF1 and the held-out BCF2/BCF3).

``draws`` posterior draws of θ (chosen at random over all chains, seeded) are run through the full simulator with the
``forward`` stage (parallel over draws). Two ensembles per QoI that has a noise block in the posterior:

* ``<qoi>``: the model output — the spread due to parameter uncertainty only;
* ``<qoi>_predictive``: the model output plus measurement noise N(0, σ_i²) with the draw's own σ_i (Eq. 4.3), i.e.
  draws of new observations. For a held-out experiment without a block of its own the noise of the same variable's
  training blocks is used (the root mean square of their σ_i when several).

Both go through the ``quantiles`` stage (reused, not copied). With ``observations`` wired, ``coverage_<qoi>`` and
``model_coverage_<qoi>`` (experiment) give the fraction of finite observations inside the band between the lowest and
the highest level (default 5 %-95 %: the 90 % band) of the predictive and of the model ensemble.
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from spflow.core.cf_metadata import UNITS_VARIABLE, udunits
from spflow.core.errors import ParameterError
from spflow.core.params import Param
from spflow.core.schema import DatasetSchema
from spflow.core.stage import Stage, StageContext
from spflow.plugins.design.parameter_map import ParameterMap
from spflow.plugins.design.schemas import SPACE
from spflow.plugins.forward.failures import drop_failed
from spflow.plugins.forward.stage import Forward
from spflow.plugins.observations import OBSERVATIONS
from spflow.plugins.statistics.quantiles import Quantiles

from .posterior import POSTERIOR, flat_theta

__all__ = ["PosteriorPredictive", "PREDICTIVE"]

#: Output schema: quantile bands over (quantile, experiment, pv) plus coverage per experiment.
PREDICTIVE = DatasetSchema(dims=("quantile", "experiment", "pv"), doc="posterior predictive bands and coverage")


def _noise_sigma(posterior: xr.Dataset, variable: str, experiment: str, rows: np.ndarray) -> np.ndarray | None:
    """σ of (variable, experiment) for the selected draws: its own block, else the RMS of the variable's blocks."""
    flat = posterior["sigma"].transpose("chain", "draw", "block").values.reshape(-1, posterior.sizes["block"])
    variables = posterior["block_variable"].values.astype(str)
    own = np.flatnonzero((variables == variable) & (posterior["block_experiment"].values.astype(str) == experiment))
    same = own if own.size else np.flatnonzero(variables == variable)
    if not same.size:
        return None
    return np.sqrt(np.mean(flat[rows][:, same] ** 2, axis=1))


def _on_grid(series: xr.DataArray, grid: np.ndarray) -> np.ndarray:
    """Finite values of ``series`` (dim pv) at the PV labels of ``grid`` (matched to 1e-9 PV; a union grid may hold one
    PV twice, e.g. 4.1 and 4.1000000000000005, with NaN at all but one), NaN elsewhere."""
    lookup = {round(float(p), 9): float(v) for p, v in zip(series["pv"].values, series.values) if np.isfinite(v)}
    return np.array([lookup.get(round(float(p), 9), np.nan) for p in grid])


class PosteriorPredictive(Stage):
    name = "posterior_predictive"
    version = "3"  # 3: every unit in UDUNITS form (issue 23)
    description = "simulator on posterior draws: quantile bands (model and with noise) and coverage of observations"
    inputs = {"posterior": POSTERIOR, "space": SPACE, "observations": OBSERVATIONS}
    optional_inputs = frozenset({"observations"})
    output = PREDICTIVE
    params = {
        "experiments": Param(list, ["BCF1", "BCF2", "BCF3"],
                             doc="corefloods to predict (training and held-out): bundled names or {name, schedule, "
                                 "params} mappings (as the forward stage's experiments)"),
        "draws": Param(int, 200, bounds=(1, 100_000), doc="posterior draws run through the simulator"),
        "levels": Param(list, [0.05, 0.5, 0.95], bounds=(0.0, 1.0), doc="quantile levels; outer two = the band"),
        "noise": Param(bool, True, doc="also build the predictive ensemble with measurement noise"),
        "seed": Param(int, 0, bounds=(0, 2**32 - 1), doc="random seed (draw choice and noise)"),
        "fixed": Param(dict, {}, doc="forward-model parameter overrides (as in the forward stage)"),
        "effects": Param(dict, {}, doc="effect strengths (as in the forward stage)"),
        "cells": Param(int, 100, bounds=(4, 5000), doc="grid cells"),
        "pv_step": Param(float, 0.1, bounds=(1e-4, 1.0), unit="PV", doc="output grid spacing"),
    }

    def __init__(self, **params):
        super().__init__(**params)
        if len(self.params["levels"]) < 2:
            raise ParameterError("stage 'posterior_predictive' parameter 'levels' needs at least two levels")
        self._forward = Forward(experiments=self.params["experiments"], fixed=self.params["fixed"],
                                effects=self.params["effects"], cells=self.params["cells"],
                                pv_step=self.params["pv_step"])

    @classmethod
    def code_fingerprint(cls) -> str:
        """Also keyed on the simulator's sources, like the forward stage."""
        return f"{super().code_fingerprint()}-{Forward.code_fingerprint()}"

    def run(self, ctx: StageContext, posterior: xr.Dataset, space: xr.Dataset,
            observations: xr.Dataset | None = None) -> xr.Dataset:
        names = [str(n) for n in posterior["param"].values]
        missing = [n for n in names if n not in space["param"].values]
        if missing:
            raise ParameterError(f"stage 'posterior_predictive': posterior parameter {missing[0]!r} is not in the "
                                 f"space {[str(n) for n in space['param'].values]}")
        theta = flat_theta(posterior)
        if self.params["draws"] > theta.shape[0]:
            raise ParameterError(f"stage 'posterior_predictive' parameter 'draws' = {self.params['draws']} exceeds the "
                                 f"{theta.shape[0]} posterior draws")
        rng = np.random.default_rng(self.params["seed"])
        rows = np.sort(rng.choice(theta.shape[0], self.params["draws"], replace=False))
        design = ParameterMap.of(space.sel(param=names)).design(theta[rows])
        ensemble, kept = drop_failed(self._forward.run(ctx, design=design), "stage 'posterior_predictive'")
        rows, ensemble = rows[kept], ensemble.drop_vars("failure", errors="ignore")
        noisy = []
        for variable in [str(v) for v in np.unique(posterior["block_variable"].values)] if self.params["noise"] else []:
            if variable not in ensemble:
                continue
            sigma = np.stack([_noise_sigma(posterior, variable, str(e), rows) for e in ensemble["experiment"].values],
                             axis=1)
            model = ensemble[variable]
            noise = sigma[:, :, None] * rng.standard_normal(model.shape)
            label = model.attrs.get("long_name", variable)
            ensemble[f"{variable}_predictive"] = (model.dims, model.values + noise,
                                                  dict(model.attrs, long_name=f"{label} with measurement noise"))
            noisy.append(variable)
        ensemble["theta"] = (("sample", "param"), theta[rows],
                             {UNITS_VARIABLE: "param_unit", "long_name": "posterior draws of the parameters run"})
        ensemble["param_unit"] = ("param", np.array([udunits(u) for u in posterior["unit"].values]),
                                  {"long_name": "UDUNITS unit of each parameter's design column"})
        ensemble["param"].attrs["long_name"] = "calibrated parameter (design column)"
        bands = Quantiles(levels=self.params["levels"]).run(ctx, ensemble=ensemble)
        bands.attrs.update(draws=int(rows.size), failed_draws=int(self.params["draws"] - rows.size),
                           band_low=min(self.params["levels"]),
                           band_high=max(self.params["levels"]), noisy_variables=" ".join(noisy))
        if observations is not None:
            self._coverage(bands, observations, noisy)
        return bands

    def _coverage(self, bands: xr.Dataset, observations: xr.Dataset, noisy: list[str]) -> None:
        """Fraction of finite observations inside the outer band, per experiment (in place)."""
        lo_q, hi_q = min(self.params["levels"]), max(self.params["levels"])
        for variable in noisy:
            for name, prefix in ((f"{variable}_predictive", "coverage"), (variable, "model_coverage")):
                fraction, count = [], []
                for e in bands["experiment"].values:
                    if variable not in observations or e not in observations["experiment"].values:
                        fraction.append(np.nan)
                        count.append(0)
                        continue
                    y = _on_grid(observations[variable].sel(experiment=e), bands["pv"].values)
                    lo = bands[name].sel(quantile=lo_q, experiment=e).values
                    hi = bands[name].sel(quantile=hi_q, experiment=e).values
                    ok = np.isfinite(y) & np.isfinite(lo) & np.isfinite(hi)
                    count.append(int(ok.sum()))
                    fraction.append(float(np.mean((y[ok] >= lo[ok]) & (y[ok] <= hi[ok]))) if ok.any() else np.nan)
                which = "predictive (with noise)" if prefix == "coverage" else "model"
                bands[f"{prefix}_{variable}"] = ("experiment", np.array(fraction), {
                    "units": "1", "long_name": f"fraction of the {variable} observations inside the {which} band"})
                bands[f"points_{variable}"] = ("experiment", np.array(count), {
                    "units": "1", "long_name": f"{variable} observations compared with the band"})
