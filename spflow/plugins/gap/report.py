"""The gap report: a netCDF-able Dataset of a :class:`~spflow.plugins.gap.diagnosis.GapDiagnosis`, and its summary.

Dataset layout (every variable has ``units``; mixed-unit tables name their units in a coordinate; log-density scores
are in nats, written ``units = "1"`` with "nats" in their ``long_name``):

* series on (``model`` = base | final, ``experiment``, ``pv``): ``prediction_<qoi>``, ``std_<qoi>`` (predictive
  standard deviation), ``whitened_<qoi>``; ``observed_<qoi>`` on (``experiment``, ``pv``); ``role`` of each
  experiment (calibration | heldout);
* ``cell`` table (QoI x experiment x slug): ``cell_n``, ``cell_chi2`` (normalised, per model), ``cell_pvalue``,
  ``cell_bias_z``, ``cell_rms`` and ``gap_rank`` (1 = largest significant gap, 0 = not a gap cell);
* ``block`` table (QoI x experiment): Ljung-Box ``whiteness_q`` / ``whiteness_pvalue``, ``rmse``, ``coverage``;
* ``signature`` table: ``signature_observed``, ``signature_predicted`` and ``signature_pvalue`` per model;
* ``change_point`` table (significant mean shifts inside slugs, both models, :mod:`~spflow.plugins.gap.change_points`):
  ``cp_model``, ``cp_variable``, ``cp_experiment``, ``cp_slug``, ``cp_pv``, ``cp_statistic``, ``cp_pvalue``,
  ``cp_shift_whitened``, ``cp_shift``;
* ``input_correlation`` table (QoI x experiment x input channel, :mod:`~spflow.plugins.gap.input_correlation`):
  ``xcorr_z`` per (model, lag), and per model the best lag ``xcorr_lag``, ``xcorr_statistic``, ``xcorr_pvalue``,
  ``xcorr_effect``, ``xcorr_significant``;
* ``candidate`` tables per greedy ``step``: ``screen_z``, ``snr``, ``absorbed``, ``fitted_strength``,
  ``delta_elpd`` (+ SEs), ``delta_elpd_loo`` (+ SE, ``pareto_k_max``; PSIS-LOO on the calibration data, reported
  only), ``heldout_ess``, ``heldout_pareto_k`` and ``heldout_mcse`` (the sampled held-out predictive's draws, option
  ``heldout_predictive = "sampled"``; NaN otherwise), ``gap_closed``, ``passes``; ``fingerprint_cos`` of the first
  step;
* ``param`` table: ``theta`` per model (units per parameter: ``param_units``, :mod:`spflow.core.cf_metadata`) and
  ``shift_fraction``;
* scalars and attrs: chi^2, p-value, gap-closed fractions, coverage, ELPD, the verdict and the ambiguity set;
  ``effects`` holds the *declared* effects only (verdict ``effect`` / ``ambiguous``), ``tried_not_declared`` every
  other refitted candidate with its single-effect strength; ``numerical_error`` (variants, forward runs, chi^2
  with measurement error only, the estimated scale with its interval and likelihood profile, RMS spread of the
  variants per block, unscaled) and the scale alone as the number ``numerical_scale``, ``discrepancy`` (the
  competitor's terms, calibration chi^2, held-out dELPD over the base), ``search`` (pool, subsets fitted,
  admissible, chosen, forward runs), ``notes`` (blocks left out of the report; the dispersivity a named dispersion
  stands for; the models whose sampled held-out score is unreliable), ``heldout_weights`` (Pareto k, effective
  sample size and Monte Carlo SE in nats of every sampled held-out predictive, the base's included, by model),
  ``path_reruns`` (the diagnosis rerun along other optimiser paths: difference step, verdict, set, effects, forward
  runs, whether it agrees; :mod:`~spflow.plugins.gap.path_stability`) and ``measurement`` (per coreflood the
  measurement model the likelihood used and whether the data gave it) as JSON.

:func:`summary` reads only the Dataset, so a report loaded from disk gives the same ``summary.json``.
"""

from __future__ import annotations

import json
from dataclasses import asdict

import numpy as np
import xarray as xr

from spflow.core.cf_metadata import UNITS_VARIABLE, udunits
from spflow.plugins.forward.parameters import PARAMETERS
from spflow.plugins.forward.run_arguments import common_grid
from spflow.plugins.forward.stage import RESPONSE_UNITS

from .diagnosis import GapDiagnosis, ModelView
from .localisation import Cell
from .quantification import block_rmse, coverage, gap_closed
from .sampled_predictive import is_unreliable
from .signatures import SIGNATURE_UNITS
from .verdict import passes

__all__ = ["report_dataset", "summary"]

_UNITS = {"dp": "Pa", "oil_cut": "1", "recovery": "1", "c_polymer_out": "ppm", "c_surfactant_out": "ppm",
          "salinity_out": "ppm"}
_SPEC_UNITS = {p.name: p.unit for p in PARAMETERS}
#: What an effect strength is (a dimensionless scale of its mechanism, docs/gap.md; ``spflow list effects``).
_STRENGTH = "effect strength (dimensionless scale of the mechanism, see spflow list effects)"


def _units_of(variables) -> list[str]:
    """The UDUNITS unit of each response variable in ``variables`` (the forward stage's ``RESPONSE_UNITS``)."""
    return [udunits(RESPONSE_UNITS[v]) for v in variables]
#: Long names of the log-density scores. They are in nats (natural-log units), written ``units = "1"``: UDUNITS reads
#: "nat" as nano technical atmospheres.
_NATS = {k: {"long_name": v} for k, v in {
    "delta_elpd": "change of expected log predictive density, candidate - reference (nats)",
    "delta_elpd_se": "standard error of delta_elpd (nats)",
    "delta_elpd_se_pointwise": "pointwise standard error of delta_elpd (nats)",
    "delta_elpd_loo": "PSIS-LOO change of expected log predictive density (nats)",
    "delta_elpd_loo_se": "standard error of delta_elpd_loo (nats)",
    "elpd_base": "out-of-sample expected log predictive density of the base model (nats)",
    "elpd_final": "out-of-sample expected log predictive density of the final model (nats)"}.items()}


def _series_vars(g: GapDiagnosis, views: list[ModelView], grid: np.ndarray, positions: dict[str, np.ndarray]):
    names = [e.name for e in g.calibration + g.heldout]
    out = {}
    for variable in g.layout_all.variables:
        obs = np.full((len(names), grid.size), np.nan)
        pred, std, white = (np.full((len(views), len(names), grid.size), np.nan) for _ in range(3))
        for b, s in zip(g.layout_all.blocks, g.layout_all.slices()):
            if b.variable != variable:
                continue
            i = names.index(b.experiment)
            cols = positions[b.experiment][b.index]
            obs[i, cols] = b.observed
            for m, v in enumerate(views):
                pred[m, i, cols], std[m, i, cols], white[m, i, cols] = v.prediction[s], v.std[s], v.whitened[s]
        u = _UNITS[variable]
        out[f"observed_{variable}"] = (("experiment", "pv"), obs, {"units": u})
        out[f"prediction_{variable}"] = (("model", "experiment", "pv"), pred, {"units": u})
        out[f"std_{variable}"] = (("model", "experiment", "pv"), std, {"units": u})
        out[f"whitened_{variable}"] = (("model", "experiment", "pv"), white, {"units": "1"})
    return out


def _score_vars(g: GapDiagnosis, grid: np.ndarray, positions: dict[str, np.ndarray]):
    """Pointwise out-of-sample log-density differences final - base on the scored points, per QoI."""
    names = [e.name for e in g.calibration + g.heldout]
    diff = g.out_of_sample_final.lpd - g.out_of_sample_base.lpd
    out = {}
    for b, s in zip(g.layout_score.blocks, g.layout_score.slices()):
        key = f"elpd_difference_{b.variable}"
        if key not in out:
            out[key] = (("experiment", "pv"), np.full((len(names), grid.size), np.nan),
                        {"units": "1", "long_name": f"pointwise out-of-sample lpd, final - base ({g.score_kind}; "
                                                 "nats)"})
        out[key][1][names.index(b.experiment), positions[b.experiment][b.index]] = diff[s]
    return out


def _slug_vars(experiments):
    n = max(len(e.schedule.slugs) for e in experiments)
    ends = np.full((len(experiments), n), np.nan)
    names = np.full((len(experiments), n), "", dtype=object)
    for i, e in enumerate(experiments):
        ends[i, : len(e.schedule.slugs)] = e.slug_ends()
        names[i, : len(e.schedule.slugs)] = [s.name for s in e.schedule.slugs]
    return {"slug_end_pv": (("experiment", "slug"), ends,
                            {"units": "1", "long_name": "injected pore volumes at the end of each slug"}),
            "slug_name": (("experiment", "slug"), names.astype(str))}


def _cell_vars(g: GapDiagnosis, views: list[ModelView]):
    base: list[Cell] = views[0].cells
    rank = {(c.variable, c.experiment, c.slug): k + 1 for k, c in enumerate(g.gap_cells)}
    coords = {
        "cell_variable": ("cell", [c.variable for c in base]),
        "cell_experiment": ("cell", [c.experiment for c in base]),
        "cell_slug": ("cell", [c.slug_name for c in base]),
        "cell_pv_start": ("cell", [c.pv_start for c in base], {"units": "1", "long_name": "injected pore volumes at "
                                                                                         "the start of the cell"}),
        "cell_pv_end": ("cell", [c.pv_end for c in base], {"units": "1", "long_name": "injected pore volumes at the "
                                                                                     "end of the cell"}),
        "cell_units": ("cell", _units_of([c.variable for c in base]),
                       {"long_name": "UDUNITS unit of each cell's variable"}),
    }
    data = {
        "cell_n": ("cell", [c.n for c in base], {"units": "1"}),
        "cell_chi2": (("model", "cell"), [[c.normalised_chi2 for c in v.cells] for v in views],
                      {"units": "1", "long_name": "mean squared whitened residual (expected 1)"}),
        "cell_pvalue": (("model", "cell"), [[c.pvalue for c in v.cells] for v in views], {"units": "1"}),
        "cell_bias_z": (("model", "cell"), [[c.bias_z for c in v.cells] for v in views], {"units": "1"}),
        "cell_rms": (("model", "cell"), [[c.rms for c in v.cells] for v in views],
                     {UNITS_VARIABLE: "cell_units", "long_name": "root-mean-square residual of the cell"}),
        "gap_rank": ("cell", [rank.get((c.variable, c.experiment, c.slug), 0) for c in base], {"units": "1"}),
    }
    return coords, data


def _block_vars(g: GapDiagnosis, views: list[ModelView]):
    blocks = g.layout_all.blocks
    slices = g.layout_all.slices()
    coords = {"block_variable": ("block", [b.variable for b in blocks]),
              "block_experiment": ("block", [b.experiment for b in blocks]),
              "block_units": ("block", _units_of([b.variable for b in blocks]),
                              {"long_name": "UDUNITS unit of each block's variable"})}
    q = [[v.ljung_box[(b.variable, b.experiment)][0] for b in blocks] for v in views]
    p = [[v.ljung_box[(b.variable, b.experiment)][1] for b in blocks] for v in views]
    rmse = [list(block_rmse(g.layout_all, v.residual).values()) for v in views]
    cov = [[coverage(v.residual[s], v.std[s], g.options.interval) for s in slices] for v in views]
    data = {
        "whiteness_q": (("model", "block"), q, {"units": "1", "long_name": "Ljung-Box Q of whitened residuals"}),
        "whiteness_pvalue": (("model", "block"), p, {"units": "1"}),
        "rmse": (("model", "block"), rmse, {UNITS_VARIABLE: "block_units", "long_name": "root-mean-square residual"}),
        "coverage": (("model", "block"), cov, {"units": "1", "long_name": f"{g.options.interval:g} interval coverage"}),
    }
    return coords, data


def _signature_vars(g: GapDiagnosis, views: list[ModelView]):
    keys = [(e, k) for e, table in views[0].signatures.items() for k in table]
    coords = {"signature_experiment": ("signature", [e for e, _ in keys]),
              "signature_name": ("signature", [k for _, k in keys]),
              "signature_units": ("signature", [udunits(SIGNATURE_UNITS[k.split(":")[0]]) for _, k in keys],
                                  {"long_name": "UDUNITS unit of each signature"})}
    data = {
        "signature_observed": ("signature", [views[0].signatures[e][k][0] for e, k in keys],
                               {UNITS_VARIABLE: "signature_units", "long_name": "observed signature"}),
        "signature_predicted": (("model", "signature"), [[v.predicted_signatures[e].get(k, np.nan) for e, k in keys]
                                                         for v in views],
                                {UNITS_VARIABLE: "signature_units", "long_name": "predicted signature"}),
        "signature_pvalue": (("model", "signature"), [[v.signatures[e][k][1] for e, k in keys] for v in views],
                             {"units": "1", "long_name": "two-sided posterior-predictive p-value"}),
    }
    return coords, data


def _change_point_vars(views: list[ModelView], models: list[str]):
    rows = [(m, c) for m, v in zip(models, views) for c in v.change_points]
    coords = {"cp_model": ("change_point", np.array([m for m, _ in rows], dtype=str)),
              "cp_variable": ("change_point", np.array([c.variable for _, c in rows], dtype=str)),
              "cp_experiment": ("change_point", np.array([c.experiment for _, c in rows], dtype=str)),
              "cp_slug": ("change_point", np.array([c.slug_name for _, c in rows], dtype=str)),
              "cp_units": ("change_point", np.array(_units_of([c.variable for _, c in rows]), dtype=str),
                           {"long_name": "UDUNITS unit of each change point's variable"})}
    data = {
        "cp_pv": ("change_point", np.array([c.pv for _, c in rows], float),
                  {"units": "1", "long_name": "injected pore volumes at the change point"}),
        "cp_statistic": ("change_point", np.array([c.statistic for _, c in rows], float),
                         {"units": "1", "long_name": "max |t| of a mean shift inside the slug"}),
        "cp_pvalue": ("change_point", np.array([c.pvalue for _, c in rows], float), {"units": "1"}),
        "cp_shift_whitened": ("change_point", np.array([c.shift_whitened for _, c in rows], float),
                              {"units": "1", "long_name": "mean shift of the whitened residuals (sigma)"}),
        "cp_shift": ("change_point", np.array([c.shift for _, c in rows], float),
                     {UNITS_VARIABLE: "cp_units", "long_name": "mean shift of the residuals (model - data)"}),
    }
    return coords, data


def _correlation_vars(views: list[ModelView]):
    keys = sorted((c.variable, c.experiment, c.channel) for c in views[0].input_correlations)
    tables = [{(c.variable, c.experiment, c.channel): c for c in v.input_correlations} for v in views]
    lags = views[0].input_correlations[0].lags if keys else np.zeros(0)
    coords = {"xcorr_variable": ("input_correlation", np.array([k[0] for k in keys], dtype=str)),
              "xcorr_experiment": ("input_correlation", np.array([k[1] for k in keys], dtype=str)),
              "xcorr_channel": ("input_correlation", np.array([k[2] for k in keys], dtype=str)),
              "xcorr_units": ("input_correlation", np.array(_units_of([k[0] for k in keys]), dtype=str),
                              {"long_name": "UDUNITS unit of each residual's variable"}),
              "lag": ("lag", lags, {"units": "1", "long_name": "lag in injected pore volumes"})}

    def table(f):
        return np.array([[f(t[k]) for k in keys] for t in tables], dtype=float).reshape(len(views), len(keys))

    data = {
        "xcorr_z": (("model", "input_correlation", "lag"),
                    np.array([[t[k].z for k in keys] for t in tables], float).reshape(len(views), len(keys),
                                                                                      lags.size),
                    {"units": "1", "long_name": "GLS z of the residual on the lagged input channel"}),
        "xcorr_lag": (("model", "input_correlation"), table(lambda c: c.lag),
                      {"units": "1", "long_name": "lag of max |z| in injected pore volumes"}),
        "xcorr_statistic": (("model", "input_correlation"), table(lambda c: c.statistic), {"units": "1"}),
        "xcorr_pvalue": (("model", "input_correlation"), table(lambda c: c.pvalue),
                         {"units": "1", "long_name": "p-value of max |z| over the lags"}),
        "xcorr_effect": (("model", "input_correlation"), table(lambda c: c.effect),
                         {UNITS_VARIABLE: "xcorr_units", "long_name": "residual change with the channel's step"}),
        "xcorr_significant": (("model", "input_correlation"), table(lambda c: c.significant).astype(np.int8),
                              {"units": "1"}),
    }
    return coords, data


def _candidate_vars(g: GapDiagnosis):
    names = [c.name for c in g.candidates]
    shape = (len(g.steps), len(names))
    tables = {k: np.full(shape, np.nan) for k in ("screen_z", "snr", "absorbed", "fitted_strength", "strength_z",
                                                  "delta_elpd",
                                                  "delta_elpd_se", "delta_elpd_se_pointwise", "gap_closed",
                                                  "chi2_calibration", "delta_elpd_loo", "delta_elpd_loo_se",
                                                  "pareto_k_max", "heldout_ess", "heldout_pareto_k",
                                                  "heldout_mcse")}
    flags = {k: np.zeros(shape, dtype=np.int8) for k in ("shortlisted", "passes", "physical")}
    for s, step in enumerate(g.steps):
        for i, name in enumerate(step.screen.names):
            j = names.index(name)
            tables["screen_z"][s, j] = step.screen.best_z()[i]
            tables["snr"][s, j] = step.screen.snr[i][-1]
            tables["absorbed"][s, j] = step.screen.absorbed(i)
        for name, score in step.scores.items():
            j = names.index(name)
            flags["shortlisted"][s, j] = 1
            tables["fitted_strength"][s, j] = score.strength
            tables["strength_z"][s, j] = score.strength_z
            tables["delta_elpd"][s, j] = score.delta_elpd
            tables["delta_elpd_se"][s, j] = score.se
            tables["delta_elpd_se_pointwise"][s, j] = score.se_pointwise
            tables["gap_closed"][s, j] = score.gap_closed
            tables["chi2_calibration"][s, j] = step.fits[name].chi2
            if name in step.out_of_sample:  # (NaN unless the held-out predictive is sampled)
                held = step.out_of_sample[name]
                tables["heldout_ess"][s, j], tables["heldout_pareto_k"][s, j] = held.ess, held.pareto_k
                tables["heldout_mcse"][s, j] = held.mcse
            if name in step.loo:
                loo = step.loo[name]
                tables["delta_elpd_loo"][s, j], tables["delta_elpd_loo_se"][s, j], tables["pareto_k_max"][s, j] = loo
            flags["passes"][s, j] = int(passes(score, g.options.rule))
            flags["physical"][s, j] = int(score.physical)
    first = g.steps[0].screen
    order = [first.names.index(n) for n in names]
    cos = first.cos[np.ix_(order, order)]
    names_of = {"fitted_strength": {"long_name": f"fitted {_STRENGTH}"},
                "heldout_ess": {"long_name": "effective sample size of the sampled held-out predictive's draws "
                                             "(NaN: linearised predictive)"},
                "heldout_pareto_k": {"long_name": "Pareto k of the sampled held-out predictive's importance weights "
                                                  "(> 0.7: unreliable; NaN: linearised predictive)"},
                "heldout_mcse": {"long_name": "Monte Carlo standard error of the candidate's sampled held-out log "
                                              "predictive density (NaN: linearised predictive)"}} | _NATS
    data = {k: (("step", "candidate"), v, {"units": "1", **names_of.get(k, {})}) for k, v in tables.items()}
    data |= {k: (("step", "candidate"), v, {"units": "1"}) for k, v in flags.items()}
    data["step_reference"] = ("step", [s.reference for s in g.steps])
    data["step_scored_against"] = ("step", [s.scored_against for s in g.steps])
    data["fingerprint_cos"] = (("candidate", "candidate_b"), cos, {"units": "1"})
    data["base_strength"] = ("candidate", [c.base for c in g.candidates],
                             {"units": "1", "long_name": f"base-model {_STRENGTH}"})
    data["physical_lower"] = ("candidate", [c.physical[0] for c in g.candidates],
                              {"units": "1", "long_name": f"lower end of the physical range of the {_STRENGTH}"})
    data["physical_upper"] = ("candidate", [c.physical[1] for c in g.candidates],
                              {"units": "1", "long_name": f"upper end of the physical range of the {_STRENGTH}"})
    return {"candidate": names, "candidate_b": names}, data


def _scalars(g: GapDiagnosis):
    cal = [e.name for e in g.calibration]
    held = [e.name for e in g.heldout]
    out = {"chi2_base": g.base_fit.chi2, "chi2_final": g.final_fit.chi2, "dof": float(g.dof),
           "chi2_pvalue": g.chi2_pvalue, "targeted_pvalue": g.targeted_pvalue,
           "gap_closed_calibration": gap_closed(g.base_fit.chi2, g.final_fit.chi2, g.dof),
           "elpd_base": g.out_of_sample_base.total, "elpd_final": g.out_of_sample_final.total}
    n_score = float(np.sum(np.isfinite(g.out_of_sample_base.whitened)))
    chi2_h0 = float(np.nansum(g.out_of_sample_base.whitened ** 2))
    chi2_h1 = float(np.nansum(g.out_of_sample_final.whitened ** 2))
    out.update(chi2_heldout_base=chi2_h0, chi2_heldout_final=chi2_h1, n_heldout=n_score,
               gap_closed_heldout=gap_closed(chi2_h0, chi2_h1, n_score))
    for label, names in (("calibration", cal), ("heldout", held)):
        rows = np.concatenate([np.full(b.index.size, b.experiment in names) for b in g.layout_all.blocks])
        for model, v in (("base", g.base_view), ("final", g.final_view)):
            out[f"coverage_{label}_{model}"] = coverage(v.residual[rows], v.std[rows], g.options.interval) \
                if rows.any() else float("nan")
    return {k: ((), float(v), {"units": "1", **_NATS.get(k, {})}) for k, v in out.items()}


def report_dataset(g: GapDiagnosis) -> xr.Dataset:
    """The gap report of a diagnosis (module docstring)."""
    views = [g.base_view, g.final_view]
    experiments = g.calibration + g.heldout
    grid, pos = common_grid([e.schedule.total_pv for e in experiments], g.options.pv_step)
    positions = {e.name: p for e, p in zip(experiments, pos)}
    data = _series_vars(g, views, grid, positions) | _score_vars(g, grid, positions) | _slug_vars(experiments)
    coords = {"model": ["base", "final"], "experiment": [e.name for e in experiments],
              "pv": ("pv", grid, {"units": "1", "long_name": "injected pore volumes"}),
              "role": ("experiment", ["calibration"] * len(g.calibration) + ["heldout"] * len(g.heldout))}
    for part in (_cell_vars(g, views), _block_vars(g, views), _signature_vars(g, views), _candidate_vars(g),
                 _change_point_vars(views, ["base", "final"]), _correlation_vars(views)):
        coords.update(part[0])
        data.update(part[1])
    params = g.base.parameters
    theta = np.array([g.base.values(g.base_fit.u), g.base.values(g.final_fit.u)])
    coords.update({"param": [p.label for p in params],
                   "param_units": ("param", [udunits(_SPEC_UNITS[p.names[0]]) for p in params],
                                   {"long_name": "UDUNITS unit of each calibrated parameter"})})
    data["theta"] = (("model", "param"), theta, {UNITS_VARIABLE: "param_units"})
    data["shift_fraction"] = ("param", (theta[1] - theta[0]) / (g.base.upper - g.base.lower),
                              {"units": "1", "long_name": "parameter shift / range"})
    data.update(_scalars(g))
    final_strengths = g.final_fit.strengths
    search = None
    if g.search is not None:
        search = {"pool": g.search_pool, "subsets_fitted": [list(k) for k in g.search.fits if k],
                  "admissible": [list(k) for k in g.search.admissible], "chosen": list(g.search.chosen),
                  "forward_runs": g.search_runs}
    numerical = None
    if g.numerical is not None:
        numerical = {"variants": g.numerical.variants, "forward_runs": g.numerical.runs,
                     "chi2_base_measurement_only": g.chi2_measurement_only,
                     "scale": None if g.numerical_scale is None else g.numerical_scale.as_dict(),
                     "rms": {f"{v}:{e}": x for (v, e), x in g.numerical.rms(g.layout_all).items()}}
    discrepancy = None
    if g.discrepancy is not None:
        discrepancy = {"terms": g.discrepancy.n_terms, "chi2_calibration": g.discrepancy.chi2,
                       "gap_closed_calibration": gap_closed(g.base_fit.chi2, g.discrepancy.chi2, g.dof),
                       "delta_elpd_heldout": None if g.out_of_sample_discrepancy is None else
                       float(np.sum(g.out_of_sample_discrepancy.lpd - g.out_of_sample_base.lpd))}
    attrs = {
        "verdict": g.verdict,
        "ambiguity_set": json.dumps(g.ambiguity),
        "effects": json.dumps([{"name": k, "strength": v} for k, v in final_strengths.items()]),
        "tried_not_declared": json.dumps([{"name": k, "strength": v} for k, v in g.tried.items()]),
        "search": json.dumps(search),
        "numerical_error": json.dumps(numerical),
        **({} if g.numerical_scale is None else {"numerical_scale": g.numerical_scale.estimate}),
        "discrepancy": json.dumps(discrepancy),
        "notes": json.dumps(g.notes),
        "heldout_weights": json.dumps({m: {"pareto_k": _f(k), "ess": _f(ess), "mcse": _f(mcse)}
                                      for m, (k, ess, mcse) in g.heldout_weights.items()}),
        "path_reruns": json.dumps([r.as_dict() for r in g.path_reruns]),
        "accepted_steps": json.dumps(g.accepted),
        "final_model": g.final_label,
        "score_kind": g.score_kind,
        "variables": " ".join(g.options.variables),
        "interval": g.options.interval,
        "alpha": g.options.alpha,
        "cells": g.base.cells,
        "pv_step": g.options.pv_step,
        "measurement": json.dumps({e.name: {"from_data": e.noise_from_data, **asdict(e.measurement)}
                                   for e in experiments}),
        "forward_runs": g.forward_runs,
        "options": json.dumps(g.options.as_dict()),   # every option as it ran, the decision rule included
        "scheme": g.base.scheme,
        "simulator_pv_step": g.base.pv_step,
    }
    return xr.Dataset(data, coords=coords, attrs=attrs)


def _f(x) -> float | None:
    x = float(x)
    return round(x, 6) if np.isfinite(x) else None


def summary(report: xr.Dataset, top_cells: int = 10) -> dict:
    """The machine-readable summary (``summary.json``) of a gap-report Dataset."""
    r = report
    ranked = []
    for j, name in enumerate(r["candidate"].values):
        row = {"name": str(name), "screen_z": _f(r["screen_z"][0, j]), "snr": _f(r["snr"][0, j]),
               "absorbed": _f(r["absorbed"][0, j]), "shortlisted": bool(r["shortlisted"][0, j])}
        if row["shortlisted"]:
            row.update(fitted_strength=_f(r["fitted_strength"][0, j]), strength_z=_f(r["strength_z"][0, j]),
                       delta_elpd=_f(r["delta_elpd"][0, j]),
                       delta_elpd_se=_f(r["delta_elpd_se"][0, j]), gap_closed=_f(r["gap_closed"][0, j]),
                       delta_elpd_loo=_f(r["delta_elpd_loo"][0, j]) if "delta_elpd_loo" in r else None,
                       delta_elpd_loo_se=_f(r["delta_elpd_loo_se"][0, j]) if "delta_elpd_loo" in r else None,
                       heldout_ess=_f(r["heldout_ess"][0, j]) if "heldout_ess" in r else None,
                       heldout_pareto_k=_f(r["heldout_pareto_k"][0, j]) if "heldout_ess" in r else None,
                       heldout_mcse=_f(r["heldout_mcse"][0, j]) if "heldout_mcse" in r else None,
                       physical=bool(r["physical"][0, j]), passes=bool(r["passes"][0, j]))
        ranked.append(row)
    def descending(x):
        return -x if x is not None else np.inf

    ranked.sort(key=lambda row: (not row["shortlisted"], descending(row.get("delta_elpd")),
                                 descending(row["screen_z"])))
    gaps = r["gap_rank"].values
    order = [int(i) for i in np.argsort(np.where(gaps > 0, gaps, np.inf)) if gaps[i] > 0][:top_cells]
    cells = [{"variable": str(r["cell_variable"].values[i]), "experiment": str(r["cell_experiment"].values[i]),
              "slug": str(r["cell_slug"].values[i]), "pv": [_f(r["cell_pv_start"][i]), _f(r["cell_pv_end"][i])],
              "n": int(r["cell_n"][i]), "normalised_chi2": _f(r["cell_chi2"][0, i]),
              "pvalue": _f(r["cell_pvalue"][0, i]), "rms": _f(r["cell_rms"][0, i]),
              "normalised_chi2_final": _f(r["cell_chi2"][1, i])} for i in order]
    base_cp = [i for i in range(r.sizes.get("change_point", 0)) if str(r["cp_model"].values[i]) == "base"]
    change = [{"variable": str(r["cp_variable"].values[i]), "experiment": str(r["cp_experiment"].values[i]),
               "slug": str(r["cp_slug"].values[i]), "pv": _f(r["cp_pv"][i]), "statistic": _f(r["cp_statistic"][i]),
               "pvalue": _f(r["cp_pvalue"][i]), "shift_whitened": _f(r["cp_shift_whitened"][i]),
               "shift": _f(r["cp_shift"][i])} for i in base_cp[:top_cells]]
    n_xc = r.sizes.get("input_correlation", 0)
    flagged = sorted((i for i in range(n_xc) if r["xcorr_significant"][0, i]),
                     key=lambda i: (float(r["xcorr_pvalue"][0, i]), -float(r["xcorr_statistic"][0, i])))
    xcorr = [{"variable": str(r["xcorr_variable"].values[i]), "experiment": str(r["xcorr_experiment"].values[i]),
              "channel": str(r["xcorr_channel"].values[i]), "lag_pv": _f(r["xcorr_lag"][0, i]),
              "z": _f(r["xcorr_z"][0, i, int(np.nanargmax(np.abs(r["xcorr_z"].values[0, i])))]),
              "pvalue": _f(r["xcorr_pvalue"][0, i]), "effect": _f(r["xcorr_effect"][0, i]),
              "significant_final": bool(r["xcorr_significant"][1, i])} for i in flagged[:top_cells]]
    rmse_ratio = {f"{v}:{e}": _f(r["rmse"][1, k] / r["rmse"][0, k]) if r["rmse"][0, k] > 0 else None
                  for k, (v, e) in enumerate(zip(r["block_variable"].values, r["block_experiment"].values))}
    scalar = {k: _f(r[k]) for k in ("chi2_base", "chi2_final", "dof", "chi2_pvalue", "targeted_pvalue",
                                    "gap_closed_calibration",
                                    "gap_closed_heldout", "chi2_heldout_base", "chi2_heldout_final", "elpd_base",
                                    "elpd_final", "coverage_calibration_base", "coverage_calibration_final",
                                    "coverage_heldout_base", "coverage_heldout_final")}
    weights = json.loads(r.attrs.get("heldout_weights", "{}"))
    return {
        "verdict": r.attrs["verdict"],
        "effects": json.loads(r.attrs["effects"]),
        "ambiguity_set": json.loads(r.attrs["ambiguity_set"]),
        "heldout_only": [str(n) for j, n in enumerate(r["candidate"].values) if r["passes"][0, j]]
        if r.attrs["verdict"] == "none" else [],
        "tried_not_declared": json.loads(r.attrs.get("tried_not_declared", "[]")),
        "accepted_steps": json.loads(r.attrs["accepted_steps"]),
        "search": json.loads(r.attrs.get("search", "null")),
        "numerical_error": json.loads(r.attrs.get("numerical_error", "null")),
        "discrepancy": json.loads(r.attrs.get("discrepancy", "null")),
        "notes": json.loads(r.attrs.get("notes", "[]")),
        "heldout_weights": weights,
        "heldout_unreliable": sorted(m for m, v in weights.items() if is_unreliable(v["pareto_k"])),
        "path_reruns": json.loads(r.attrs.get("path_reruns", "[]")),
        "final_model": r.attrs["final_model"],
        "score": r.attrs["score_kind"],
        "ranked_effects": ranked,
        "gap_cells": cells,
        "change_points": change,
        "change_points_final": int(r.sizes.get("change_point", 0) - len(base_cp)),
        "input_correlations": xcorr,
        "gap_closed": {"calibration": scalar["gap_closed_calibration"], "heldout": scalar["gap_closed_heldout"]},
        "rmse_ratio": rmse_ratio,
        "coverage": {k.replace("coverage_", ""): v for k, v in scalar.items() if k.startswith("coverage_")},
        "fit": {k: v for k, v in scalar.items() if not k.startswith(("coverage_", "gap_closed"))},
        "parameter_shift": {str(p): {"base": _f(r["theta"][0, i]), "final": _f(r["theta"][1, i]),
                                     "fraction_of_range": _f(r["shift_fraction"][i]),
                                     "units": str(r["param_units"].values[i])}
                            for i, p in enumerate(r["param"].values)},
        "forward_runs": int(r.attrs["forward_runs"]),
        # how the diagnosis ran: every option, and the base model's numerics (absent from reports written before)
        "settings": {"options": json.loads(r.attrs.get("options", "null")), "cells": int(r.attrs["cells"]),
                     "measurement": json.loads(r.attrs.get("measurement", "null")),
                     "scheme": r.attrs.get("scheme"),
                     "simulator_pv_step": _f(r.attrs["simulator_pv_step"]) if "simulator_pv_step" in r.attrs
                     else None},
    }
