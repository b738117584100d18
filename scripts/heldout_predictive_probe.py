"""Probe of the held-out score on named twins: the linearised (Laplace) predictive the diagnosis uses against an
importance-sampled posterior predictive, for the base fit, every candidate refitted in the first step and the
truth itself (docs/gap.md, Not done (yet): why unattributed twins lose their truth).

``python scripts/heldout_predictive_probe.py 'single:dispersion#29' ... [--draws 200] [--cells 30]``

Each twin is regenerated from its seed exactly as ``scripts/gap_validation.py`` made it (Δp + oil-cut likelihood,
BCF1 calibration, BCF2 held out) and diagnosed. For each model -- the calibrated base, every candidate refitted in
the diagnosis's first step, and, for a single-effect twin, the truth (true parameters and strength, no fit) -- it
prints

* ``laplace``: the held-out log predictive density of :func:`~spflow.plugins.gap.predictive_scores.predictive`
  (mean at the model's point, covariance ``I + A C A'`` from the calibration Jacobian), the diagnosis's score;
* ``sampled``: the posterior predictive the option ``heldout_predictive = "sampled"`` scores with
  (:mod:`~spflow.plugins.gap.sampled_predictive`: ``log sum_k w_k N(y_held; y_held(z_k), I)`` over draws of the
  Laplace posterior truncated to the unit box, importance-weighted to "uniform prior on the box x calibration
  likelihood"), with ``--draws`` draws and ``--seed`` as the draws' seed. Its effective sample size and the Pareto
  k of the weights (k > 0.7 unreliable) say how far to trust it.

Both columns are reported relative to the base model's, as the diagnosis compares them (dELPD over the base).
"""

from __future__ import annotations

import argparse
import importlib.util
from pathlib import Path

import numpy as np

from spflow.plugins.gap.diagnosis import Options, diagnose
from spflow.plugins.gap.least_squares import Fit, WhitenedProblem
from spflow.plugins.gap.predictive_scores import predictive
from spflow.plugins.gap.prediction import Predictor
from spflow.plugins.gap.sampled_predictive import sampled_predictive

_spec = importlib.util.spec_from_file_location("gap_validation", Path(__file__).with_name("gap_validation.py"))
gv = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(gv)


def sampled_lpd(predictor: Predictor, g, model: Fit, draws: int, seed: int) -> tuple[float, float, float]:
    """(log predictive density of the held-out data, effective sample size, Pareto k) of ``model``'s sampled
    posterior predictive, as ``heldout_predictive = "sampled"`` computes it
    (:func:`~spflow.plugins.gap.sampled_predictive.sampled_predictive`)."""
    problems = [WhitenedProblem(predictor, layout, model.candidates, len(g.base.parameters), g.options.diff_step)
                for layout in (g.layout_fit, g.layout_score)]
    w = sampled_predictive(problems[0].residuals, problems[1].residuals, model, tau=g.options.nuisance_scale,
                           draws=draws, seed=seed)
    return w.total, w.ess, w.pareto_k


def probe(twin_id: str, cells: int, draws: int, seed: int) -> list[str]:
    specs = gv.scenarios(60, 30, 30, 30)
    [(spec, index)] = gv.select(specs, [twin_id])
    base, truth, data = gv.twin(spec, cells, 20260101 + 1000 * index)
    g = diagnose([data[0]], [data[1]], base, gv.CATALOGUE, Options(variables=("dp", "oil_cut")))
    predictor = Predictor(base, g.calibration + g.heldout)
    step = g.steps[0]
    rows = [("base fit", g.base_fit)] + sorted(((name, f) for name, f in step.fits.items()),
                                               key=lambda nf: -step.scores[nf[0]].delta_elpd)
    if len(truth["effects"]) == 1:  # the truth itself: true parameters and strength, no fit
        name, strength = next(iter(truth["effects"].items()))
        candidate = next(c for c in g.candidates if c.name == name)
        z = np.append(truth["u"], candidate.unit(strength))
        problem = WhitenedProblem(predictor, g.layout_fit, (candidate,), len(base.parameters), g.options.diff_step)
        residual = problem.fun(z)
        rows.append((f"truth ({name} = {strength:.3g})",
                     Fit(z, (candidate,), len(base.parameters), residual, problem.jac(z, residual), 0, "the truth")))
    values = {label: (predictive(predictor, g.layout_score, m, g.options.nuisance_scale, g.options.diff_step).total,
                      *sampled_lpd(predictor, g, m, draws, seed)) for label, m in rows}
    ref = values["base fit"]
    lines = [f"{twin_id}: truth {truth['effects'] or truth['fixed'] or 'none'}; verdict {g.verdict} {g.ambiguity}",
             "| model | calibration chi2 | laplace dELPD (SE) | sampled dELPD | ESS | Pareto k |",
             "|---|---|---|---|---|---|"]
    for label, m in rows:
        lap, smp, ess, k = values[label]
        se = f" ({step.scores[label].se:.1f})" if label in step.scores else ""
        lines.append(f"| {label} | {m.chi2:.1f} | {lap - ref[0]:+.1f}{se} | {smp - ref[1]:+.1f} | {ess:.1f} | "
                     f"{k:.2f} |")
    return lines


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("twins", nargs="+", help="twin ids as in scripts/gap_validation.py, e.g. 'single:dispersion#29'")
    p.add_argument("--draws", type=int, default=200)
    p.add_argument("--cells", type=int, default=30)
    p.add_argument("--seed", type=int, default=0, help="seed of the draws (Options.seed; default 0, as a diagnosis)")
    args = p.parse_args()
    for t in args.twins:
        print("\n".join(probe(t, args.cells, args.draws, args.seed)), "\n", flush=True)


if __name__ == "__main__":
    main()
