"""The ``slug_design`` stage: stochastic two-objective slug-size design with EEIHV (thesis §4.7, Eq. 4.13).

Design variables x = (s_htds, s_sp, s_p) ∈ [0.1, 1.0]³ PV (:mod:`.slug_schedule`, Eq. 4.10); objectives, both
minimised by :func:`.bgo_loop.run_bgo`: -NPV [M$] (Eqs. 4.7-4.12, :mod:`.economics`, :mod:`.oil_price`) and max Δp
[kPa], one realisation (posterior draw θ, price path S) per evaluation (:mod:`.objectives`). With a ``posterior``
(the MCMC stage's output) θ is drawn from all its chains and draws; without one the simulator runs at its Table 2.4
defaults (plus ``fixed``), so only the price path is random.

The output holds every evaluation (design, noisy objectives, GP projections, the posterior draw used), the projected
fronts after selected iterations and after the last one, each with the front uncertainty of that iteration's GPs
(empirical attainment function of sampled fronts, Vorob'ev expectation and deviation; Figs. 4.7-4.8), the knee design
by minimum distance to the utopia point (TMDSM), the knee design's responses over ``knee_draws`` posterior draws with
one price path each (Figs. 4.9-4.10) and sample price paths of the oil price model (Fig. 4.6). Units are in each
variable's ``units`` attribute, or per element (:mod:`spflow.core.cf_metadata`): objectives in the
``objective_units`` coordinate, ``1e6`` (million US dollars, M$: UDUNITS has no currency, so money is the scaled
number 1e6 with ``currency = "USD"``) and ``kPa``, design variables in ``design_units`` (pore volumes, "1").
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
import xarray as xr

from spflow.core.cf_metadata import CURRENCY, UNITS_VARIABLE
from spflow.core.errors import ParameterError
from spflow.core.params import Param
from spflow.core.schema import DatasetSchema, Variable
from spflow.core.stage import Stage, StageContext
from spflow.plugins.calibration.posterior import POSTERIOR, flat_theta
from spflow.plugins.design.parameter_map import ParameterMap
from spflow.plugins.forward.effects import default_registry
from spflow.plugins.forward.parameters import resolve_params
from spflow.plugins.forward.stage import Forward

from .economics import Economics, ScaleUp
from .knee import knee_point
from .objectives import OBJECTIVE_UNITS, OBJECTIVES, NoisyObjective, Realisations, SlugDesignProblem
from .oil_price import OilPriceModel
from .slug_schedule import DESIGN_VARIABLES, REFERENCE, SlugReference, design_bounds, minimum_total_pv

if TYPE_CHECKING:
    from .bgo_loop import BGOResult

__all__ = ["SlugDesign", "SLUG_DESIGN"]

#: Output schema (the evaluations, the projected front and the knee design).
SLUG_DESIGN = DatasetSchema(
    dims=("evaluation", "design_var", "objective"),
    variables={
        "design": Variable(("evaluation", "design_var"), units_variable="design_units",
                           long_name="slug sizes of each evaluated design"),
        "observed": Variable(("evaluation", "objective"), units_variable="objective_units",
                             long_name="objective values of each evaluation"),
        "projected": Variable(("evaluation", "objective"), units_variable="objective_units",
                              long_name="objectives projected under the drift"),
        "on_front": Variable(("evaluation",), kind="b", long_name="on the projected Pareto front"),
        "knee_design": Variable(("design_var",), units="1", long_name="slug sizes of the knee design (pore volumes)"),
        "knee_projected": Variable(("objective",), units_variable="objective_units",
                                   long_name="projected objectives of the knee design"),
        "design_units": Variable(("design_var",), kind="U", long_name="unit of each design variable"),
        "objective_units": Variable(("objective",), kind="U", long_name="unit of each objective"),
    },
    attrs=("drift", "steps_per_year", "total_pv"),
    doc="EEIHV slug-size design: evaluations, projected Pareto front, front uncertainty and knee design (§4.7)",
)

_PRICE_PATHS = 20  # sample paths kept for Fig. 4.6
_PRICE_TIMES = 2000  # about this many times kept per path


def _snapshot_recorder(wanted: set[int], store: dict[int, BGOResult], ctx: StageContext, max_iter: int):
    """A run_bgo callback keeping the partial result after each wanted number of BGO iterations (and the last), and
    reporting the iterations done as progress (of ``max_iter``; at a stop before it, of the iterations done)."""
    def record(result: BGOResult) -> None:
        done = int(result.iteration.max())
        running = result.stop_reason == "running"
        if done in wanted or not running:
            store[done] = result
        ctx.report_progress(done, max_iter if running else done, "BGO iterations")
    return record


class SlugDesign(Stage):
    name = "slug_design"
    version = "5"  # 5: every unit in UDUNITS form (issue 23)
    description = "slug-size design under price and parameter uncertainty: EEIHV on -NPV and max dp (thesis §4.7)"
    inputs = {"posterior": POSTERIOR}
    optional_inputs = frozenset({"posterior"})
    output = SLUG_DESIGN
    params = {
        "drift": Param(float, 1.0e-5, bounds=(-1.0, 1.0), unit="1/step", doc="oil price drift μ of Eq. 4.12"),
        "volatility": Param(float, 1.0e-4, bounds=(0.0, 1.0), unit="1/sqrt(step)",
                            doc="oil price volatility α of Eq. 4.12"),
        "initial_price": Param(float, 75.0, bounds=(1e-3, 1e4), unit="$/bbl", doc="S(t_0) of Eq. 4.12"),
        "steps_per_year": Param(int, 365, bounds=(1, 1_000_000), unit="1/year",
                                doc="random-walk steps per year: the time unit of drift and volatility"),
        "pore_volume": Param(float, 1.0e5, bounds=(1.0, 1.0e12), unit="bbl", doc="field pattern pore volume V_p"),
        "injection_rate": Param(float, 3.5 / 13.0, bounds=(1e-4, 100.0), unit="PV/year",
                                doc="field injection rate q; the project ends at 1 PV + 13 q"),
        "n_init": Param(int, 20, bounds=(2, 1000), doc="Latin-hypercube initial designs"),
        "max_iter": Param(int, 100, bounds=(0, 10_000), doc="maximum BGO iterations"),
        "min_iter": Param(int, 10, bounds=(0, 10_000), doc="iterations before the relative EEIHV stopping rule"),
        "rtol": Param(float, 1.0e-2, bounds=(0.0, 1.0), doc="stop when max EEIHV / first max EEIHV < rtol"),
        "batch": Param(int, 1, bounds=(1, 64), doc="designs suggested per iteration (Kriging believer)"),
        "snapshots": Param(list, [1, 50], bounds=(0, 10_000),
                           doc="iterations after which the front and its uncertainty are kept (and after the last)"),
        "n_fronts": Param(int, 200, bounds=(2, 100_000), doc="sampled fronts for the front uncertainty"),
        "knee_draws": Param(int, 50, bounds=(1, 100_000), doc="posterior draws run at the knee design"),
        "cells": Param(int, 100, bounds=(4, 5000), doc="simulator grid cells"),
        "pv_step": Param(float, 0.01, bounds=(1e-4, 0.1), unit="PV", doc="simulator output spacing"),
        "fixed": Param(dict, {}, doc="simulator parameter overrides (UTCHEM names) applied to every run (a study's "
                                     "reference flood: its core, rate and fluids)"),
        "effects": Param(dict, {}, doc="effect name -> strength of every run (as the forward stage's)"),
        "reference_flood": Param(dict, {}, doc="schedule ({name, slugs}) of the reference flood whose SP slug and "
                                               "polymer drive set Eq. 4.10's reference; {} = Table 4.2's"),
        "seed": Param(int, 0, bounds=(0, 2**32 - 1), doc="random seed (LHS, GP restarts, draws, price paths)"),
        "reference": Param(list, [0.0, 50.0],
                           doc="hypervolume reference [E[NPV] M$, E[max dp] kPa]: designs losing money or above "
                               "the pressure limit add nothing; [] = the adaptive rule of docs/eeihv.md"),
    }

    @classmethod
    def code_fingerprint(cls) -> str:
        """Also keyed on the simulator's sources, like the forward stage."""
        return f"{super().code_fingerprint()}-{Forward.code_fingerprint()}"

    def realisations(self, posterior: xr.Dataset | None) -> Realisations:
        """The objectives' setting and random draws from the parameters (validated here, before any simulation)."""
        p = self.params
        price = OilPriceModel(s0=p["initial_price"], alpha=p["volatility"], mu=p["drift"],
                              steps_per_year=p["steps_per_year"])
        scale = ScaleUp(pore_volume_bbl=p["pore_volume"], injection_rate_pv_per_year=p["injection_rate"])
        economics = Economics()
        if scale.end_pv(economics.years) <= minimum_total_pv():
            raise ParameterError(
                f"stage 'slug_design' parameter 'injection_rate' = {p['injection_rate']!r} PV/year gives "
                f"{scale.end_pv(economics.years):.3g} PV in {economics.years} years; it must exceed "
                f"{(minimum_total_pv() - scale.start_pv) / economics.years:.4g} PV/year so that the IWF, three slugs "
                f"of up to 1 PV and an extended water flood fit in the project life")
        problem = SlugDesignProblem(price=price, scale=scale, economics=economics, fixed=dict(p["fixed"]),
                                    cells=p["cells"], pv_step=p["pv_step"], reference=self.reference,
                                    effects=dict(p["effects"]))
        if posterior is None:
            return Realisations(problem)
        return Realisations(problem, flat_theta(posterior), ParameterMap.of(posterior))

    def __init__(self, **params):
        super().__init__(**params)
        self._reference()  # a malformed reference fails when the pipeline is planned, before any work
        flood = self.params["reference_flood"]
        try:
            self.reference = SlugReference.from_schedule(flood) if flood else REFERENCE
        except ValueError as exc:
            raise ParameterError(f"stage 'slug_design' parameter 'reference_flood': {exc}") from None
        resolve_params(self.params["fixed"])
        default_registry().resolve(self.params["effects"])

    def _reference(self) -> np.ndarray | None:
        """The reference point in the minimised objectives (-NPV, max dp), or None for the adaptive rule."""
        ref = self.params["reference"]
        if not ref:
            return None
        if len(ref) != 2 or not all(isinstance(v, (int, float)) and np.isfinite(v) for v in ref):
            raise ParameterError(f"stage 'slug_design' parameter 'reference' must be [] or [NPV in M$, max dp in "
                                 f"kPa] (two finite numbers), got {ref!r}")
        return np.array([-float(ref[0]), float(ref[1])])

    def run(self, ctx: StageContext, posterior: xr.Dataset | None = None) -> xr.Dataset:
        from .bgo_loop import run_bgo  # GPy, SciPy's optimisers and moocore load when a design runs

        p = self.params
        reference = self._reference()
        draws = self.realisations(posterior)
        parallel = ctx.parallel()
        objective = NoisyObjective(draws, parallel, seed=p["seed"])
        snapshots: dict[int, BGOResult] = {}
        result = run_bgo(objective, design_bounds(), n_init=p["n_init"], max_iter=p["max_iter"], rtol=p["rtol"],
                         min_iter=p["min_iter"], batch=p["batch"], seed=p["seed"], reference=reference,
                         callback=_snapshot_recorder(set(p["snapshots"]), snapshots, ctx, p["max_iter"]))
        out = result.to_dataset(design_names=DESIGN_VARIABLES, design_units=("1",) * 3,
                                objective_names=OBJECTIVES, objective_units=OBJECTIVE_UNITS)
        out["posterior_draw"] = ("evaluation", np.array([e["draw"] for e in objective.log]),
                                 {"units": "1", "description": "flat posterior draw index (-1: default parameters)"})
        out["tertiary_oil"] = ("evaluation", np.array([e["oil_pv"] for e in objective.log]),
                               {"units": "1", "description": "oil produced after the IWF, core pore volumes"})
        out = out.merge(self._snapshots(snapshots, result.X.shape[0]))
        knee = self._knee(out)
        out = out.merge(knee).merge(self._knee_runs(ctx, draws, knee["knee_design"].values, parallel))
        out = out.merge(self._price_paths(draws.problem.price, draws.problem.economics.years))
        out.attrs.update(self._attrs(draws))
        return out

    # ----- output pieces ------------------------------------------------------------------------------------------
    def _snapshots(self, snapshots: dict[int, BGOResult], n: int) -> xr.Dataset:
        """Per kept iteration (coordinate ``snapshot``): projected values and front membership (NaN/False for later
        evaluations) and the front uncertainty of that iteration's GPs: the EAF attainment surfaces (points
        ``eaf_point`` with their level), the Vorob'ev expectation (points ``vorob_point``), threshold and deviation."""
        from .front_uncertainty import front_uncertainty

        keys = sorted(snapshots)
        projected = np.full((len(keys), n, 2), np.nan)
        on_front = np.zeros((len(keys), n), dtype=bool)
        eaf, eaf_at, vorob, vorob_at, threshold, deviation = [], [], [], [], [], []
        for i, k in enumerate(keys):
            r = snapshots[k]
            projected[i, :r.X.shape[0]] = r.projected
            on_front[i, r.front_index] = True
            unc = front_uncertainty(r, n_fronts=self.params["n_fronts"], seed=self.params["seed"])
            eaf.append(unc.eaf)
            eaf_at.append(np.full(unc.eaf.shape[0], k))
            vorob.append(unc.vorob_expectation)
            vorob_at.append(np.full(unc.vorob_expectation.shape[0], k))
            threshold.append(unc.vorob_threshold)
            deviation.append(unc.vorob_deviation)
        per_objective = {UNITS_VARIABLE: "objective_units"}
        eaf, vorob = np.vstack(eaf), np.vstack(vorob)
        return xr.Dataset({
            "snapshot_projected": (("snapshot", "evaluation", "objective"), projected,
                                   {**per_objective, "description": "GP means at the designs evaluated by then"}),
            "snapshot_on_front": (("snapshot", "evaluation"), on_front, {"units": "1"}),
            "eaf_objectives": (("eaf_point", "objective"), eaf[:, :2],
                               {**per_objective, "description": "attainment-surface points of the sampled fronts"}),
            "eaf_level": ("eaf_point", eaf[:, 2], {"units": "%", "description": "attainment level of the point"}),
            "eaf_snapshot": ("eaf_point", np.concatenate(eaf_at), {"units": "1", "long_name": "BGO iteration"}),
            "vorob_expectation": (("vorob_point", "objective"), vorob, per_objective),
            "vorob_snapshot": ("vorob_point", np.concatenate(vorob_at), {"units": "1", "long_name": "BGO iteration"}),
            "vorob_threshold": ("snapshot", np.array(threshold), {"units": "%"}),
            "vorob_deviation": ("snapshot", np.array(deviation),
                                {"units": "({})*({})".format(*OBJECTIVE_UNITS), "currency": CURRENCY,
                                 "long_name": "Vorob'ev deviation (M$: million US dollars, times kPa)"}),
        }, coords={"snapshot": ("snapshot", np.array(keys), {"units": "1", "long_name": "BGO iteration"})})

    @staticmethod
    def _knee(out: xr.Dataset) -> xr.Dataset:
        front = np.flatnonzero(out["on_front"].values)
        values = out["projected"].values[front]
        row = int(front[knee_point(values)])
        return xr.Dataset({
            "knee_index": ((), row, {"units": "1", "description": "evaluation of the knee design (TMDSM)"}),
            "knee_design": ("design_var", out["design"].values[row], {"units": "1"}),
            "knee_projected": ("objective", out["projected"].values[row],
                               {UNITS_VARIABLE: "objective_units"}),
        })

    def _knee_runs(self, ctx: StageContext, draws: Realisations, x: np.ndarray, parallel) -> xr.Dataset:
        """The knee design over ``knee_draws`` realisations (posterior draw and price path each): Figs. 4.9-4.10.
        Without a posterior the simulation is deterministic and is run once."""
        from joblib import delayed  # loads when a design runs, not when the stage is listed

        problem = draws.problem
        n = self.params["knee_draws"] if draws.theta is not None else 1
        xi = [draws.draw(s) for s in np.random.SeedSequence([self.params["seed"], 1]).spawn(n)]
        runs = parallel(delayed(problem.response)(x, theta) for _, theta, _ in ctx.progress(xi, what="knee draws"))
        values = np.array([problem.outcome(r, x, prices) for r, (_, _, prices) in zip(runs, xi)])
        pv = runs[0]["pv"].values
        series = {name: np.stack([r[name].values for r in runs]) for name in ("dp", "oil_cut", "recovery")}
        return xr.Dataset({
            "knee_dp": (("knee_draw", "pv"), series["dp"] / 1e3, {"units": "kPa"}),
            "knee_oil_cut": (("knee_draw", "pv"), series["oil_cut"], {"units": "1"}),
            "knee_recovery": (("knee_draw", "pv"), series["recovery"], {"units": "1"}),
            "knee_npv": ("knee_draw", -values[:, 0], {"units": OBJECTIVE_UNITS[0], "currency": CURRENCY,
                                                      "long_name": "NPV of the knee design (M$: million US dollars)"}),
            "knee_max_dp": ("knee_draw", values[:, 1], {"units": "kPa"}),
            "knee_posterior_draw": ("knee_draw", np.array([i for i, _, _ in xi]), {"units": "1"}),
        }, coords={"pv": ("pv", pv, {"units": "1", "long_name": "injected pore volumes"}),
                   "knee_draw": ("knee_draw", np.arange(n),
                                 {"units": "1", "long_name": "realisation of the knee design"})})

    def _price_paths(self, price: OilPriceModel, years: int) -> xr.Dataset:
        """Sample paths of Eq. 4.12 (Fig. 4.6), kept at no more than about ``_PRICE_TIMES`` times per path."""
        paths = price.paths(years, _PRICE_PATHS, rng=np.random.SeedSequence([self.params["seed"], 2]))
        times = price.times(years)
        keep = np.unique(np.r_[np.arange(0, times.size, max(1, times.size // _PRICE_TIMES)), times.size - 1])
        return xr.Dataset({"price_path": (("price_sample", "time"), paths[:, keep],
                                          {"units": "1/bbl", "currency": CURRENCY,
                                           "long_name": "oil price (US dollars per barrel)"})},
                          coords={"time": ("time", times[keep], {"units": "year"}),
                                  "price_sample": ("price_sample", np.arange(_PRICE_PATHS),
                                                   {"units": "1", "long_name": "sample price path"})})

    def _attrs(self, draws: Realisations) -> dict:
        problem = draws.problem
        e, s = problem.economics, problem.scale
        return {
            "drift": self.params["drift"], "volatility": self.params["volatility"],
            "initial_price": self.params["initial_price"], "steps_per_year": self.params["steps_per_year"],
            "annual_log_drift": problem.price.annual_log_drift, "total_pv": problem.total_pv,
            "pore_volume_bbl": s.pore_volume_bbl, "injection_rate_pv_per_year": s.injection_rate_pv_per_year,
            "project_start_pv": s.start_pv, "capital_usd": e.capital_usd, "discount_rate": e.discount_rate,
            "project_years": e.years, "tde_usd_per_year": e.tde_usd_per_year,
            "chemical_prices_usd_per_lb": f"salt {e.salt_usd_per_lb}, surfactant {e.surfactant_usd_per_lb}, "
                                          f"polymer {e.polymer_usd_per_lb}",
            "reference_concentrations": problem.reference.describe() + " (Eq. 4.10; "
                                        + ("Table 4.2" if not self.params["reference_flood"] else
                                           f"from {self.params['reference_flood'].get('name', 'the study')}") + ")",
            "reference_flood": problem.reference.to_json(),
            "parameters": "Table 2.4 defaults (deterministic)" if draws.theta is None else "posterior draws",
            "posterior_draws": 0 if draws.theta is None else int(draws.theta.shape[0]),
            "objective_1": "-NPV [M$] (Eq. 4.7), minimised", "objective_2": "max dp [kPa], minimised",
        }
