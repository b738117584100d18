"""The next experiment for a permeability-reduction / polymer-viscosity ambiguity on a BCF1-like flood (issue 20).

The reference is BCF1 with its chase water cut to ``--chase-pv`` (0.3 PV): a twin (60 cells, the model's default
effects: permeability reduction and shear thinning on, documented lab noise, seed 0) is calibrated twice on its dp
and oil cut, each time over the polymer viscosity coefficients AP1 and AP3:

* ``permeability_reduction`` — the base with its permeability reduction (R_k, Eq. 2.7) on;
* ``viscosity`` — the same base with permeability reduction off: the viscosity law absorbs the Delta-p.

With the short chase water the residual resistance hardly shows and both fit the flood (the weak identification
of permeability reduction reported in issue 20); with BCF1's own 1.27 PV chase water they do not. Both carry their linearised calibration covariance. The script ranks the design space of BCF1
(:func:`spflow.plugins.gap.design_space.design_space`) by the worst hypothesis's decision accuracy, prints the
table, and writes the proposal (``next_experiment.toml``, ``next_experiment.json``, the study experiment
``next_experiment_study.toml``) and the table (``next_experiment.nc``) into ``--out``. ``--check-ranks`` compares
the predicted decision accuracy of some designs with the accuracy realised on simulated lab corefloods
(:func:`spflow.plugins.gap.design_check.realised_accuracy`). ``--nested`` ranks the diagnosis's own form of the question instead: the
base without permeability reduction against "base + permeability_reduction" with the strength freed.

    .venv/bin/python scripts/next_experiment_example.py [--cells 60] [--seed 0] [--chase-pv 0.3] [--nested] [--parameter-draws N]
        [--check-ranks 1,5 --seeds 30] [--out DIR]
"""

from __future__ import annotations

import argparse
import json
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

from spflow.plugins.forward.schedule import BCF_SCHEDULES
from spflow.plugins.gap.base_model import BaseModel
from spflow.plugins.gap.catalogue import candidates_for
from spflow.plugins.gap.design_check import realised_accuracy
from spflow.plugins.gap.layout import make_layout
from spflow.plugins.gap.least_squares import fit
from spflow.plugins.gap.next_experiment import hypotheses_from_fits, rank_designs
from spflow.plugins.gap.observed import load_experiments
from spflow.plugins.gap.prediction import Predictor
from spflow.plugins.gap.proposal import write_proposal
from spflow.study.proposed_experiment import study_experiment_toml
from spflow.synthetic import NoiseModel, make_coreflood

PARAMETERS = {"AP1": [1.0, 60.0], "AP3": [10.0, 600.0]}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cells", type=int, default=60)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--chase-pv", type=float, default=0.3)
    ap.add_argument("--nested", action="store_true")
    ap.add_argument("--parameter-draws", type=int, default=0, help="0: linearised parameter uncertainty")
    ap.add_argument("--truth-draws", type=int, default=20,
                    help="the truth's forward runs at parameter draws that make the simulated lab data (0: data from "
                         "its linearised predictive distribution, the method before 2026-11-27)")
    ap.add_argument("--no-dispersion", action="store_true",
                    help="the decision rule without the diagnosis's over-dispersion correction of the SE")
    ap.add_argument("--check-ranks", default="", metavar="R1,R2,...",
                    help="designs whose predicted accuracy to check on simulated lab corefloods")
    ap.add_argument("--seeds", type=int, default=30, help="simulated corefloods per hypothesis for --check-ranks")
    ap.add_argument("--out", default="out/next_experiment")
    args = ap.parse_args(argv)
    start = time.perf_counter()
    bcf1 = BCF_SCHEDULES["BCF1"]
    reference = replace(bcf1, slugs=bcf1.slugs[:-1] + (replace(bcf1.slugs[-1], pv=args.chase_pv),), name="BCF1s")
    data = make_coreflood(reference, {}, noise=NoiseModel(), seed=args.seed, cells=args.cells, experiment="BCF1s")
    [exp] = load_experiments([data], 0.1)
    layout = make_layout([exp], ["dp", "oil_cut"])
    without = BaseModel.from_mapping({"cells": args.cells, "effects": {"permeability_reduction": 0.0},
                                      "parameters": PARAMETERS})
    u0 = without.default_unit()
    if args.nested:
        [candidate] = candidates_for(["permeability_reduction"], without.effects)
        predictor = Predictor(without, [exp])
        fits = {"base": fit(predictor, layout, [u0]),
                "base+permeability_reduction": fit(predictor, layout, [np.concatenate((u0, [candidate.unit(1.0)]))],
                                                   (candidate,))}
        bases = {}
    else:
        bases = {"permeability_reduction": BaseModel.from_mapping({"cells": args.cells, "parameters": PARAMETERS}),
                 "viscosity": without}
        fits = {name: fit(Predictor(b, [exp]), layout, [u0]) for name, b in bases.items()}
    dof = layout.size - len(PARAMETERS)
    for name, f in fits.items():
        base = bases.get(name, without)
        values = ", ".join(f"{k} = {v:.4g}" for k, v in zip(base.labels, base.values(f.u)))
        extra = "".join(f", {k} = {v:.3g}" for k, v in f.strengths.items())
        print(f"{name}: chi2 = {f.chi2:.1f} on {dof} dof ({values}{extra})")
    hypotheses = hypotheses_from_fits(fits, bases=bases)
    table = rank_designs(hypotheses, without, exp, parameter_draws=args.parameter_draws, truth_draws=args.truth_draws,
                         dispersion=not args.no_dispersion)
    names = list(table["truth"].values)
    print(f"\n{'rank':>4} {'worst acc.':>10} {'accuracy':>16} {'E[log ratio] (nat)':>22} {'h':>5}  design")
    for i in range(table.sizes["design"]):
        r = table.isel(design=i)
        acc = " / ".join(f"{x:.2f}" for x in r["accuracy"].values)
        kl = " / ".join(f"{float(r['expected_log_ratio'].sel(truth=a, alternative=b)):.1f}"
                        for a in names for b in names if a != b)
        print(f"{int(r['rank']):>4} {float(r['worst_accuracy']):>10.2f} {acc:>16} {kl:>22} "
              f"{float(r['duration']):>5.1f}  {r['label'].values}")
        shares = json.loads(str(r["separation_by_slug"].values))
        print(f"{'':>62}separated by {', '.join(f'{k} {v:.2f}' for k, v in list(shares.items())[:3])}")
    out = Path(args.out)
    paths = write_proposal(table, out)
    text, missing = study_experiment_toml("next_experiment", paths["schedule"].name, exp.core, exp.measurement,
                                          exp.name)
    (out / "next_experiment_study.toml").write_text(text)
    if missing:
        print(f"next_experiment_study.toml: fill in {', '.join(missing)} (the reference coreflood does not state them)")
    table.to_netcdf(out / "next_experiment.nc")
    print(f"\naccuracy and log ratios per hypothesis: {' / '.join(names)} (truth first)")
    for rank in [int(r) for r in args.check_ranks.split(",") if r.strip()]:
        realised = realised_accuracy(table, hypotheses, without, exp, rank, seeds=args.seeds,
                                     dispersion=not args.no_dispersion)
        predicted = table["accuracy"].values[rank - 1]
        print(f"design {rank}: predicted accuracy {' / '.join(f'{x:.2f}' for x in predicted)}, realised on "
              f"{args.seeds} simulated corefloods {' / '.join(f'{x:.2f}' for x in realised.values)}")
    print(f"proposal: {paths['schedule']} and {paths['rationale']}; {table.attrs['forward_runs']} forward runs, "
          f"{time.perf_counter() - start:.0f} s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
