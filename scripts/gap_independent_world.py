"""Gap diagnosis on corefloods spflow's default numerics did not make (issue 20, "independent world", reduced).

The "truth" is spflow itself at very different numerics: first-order upwind (``scheme="upwind"``) on a grid
``--refine`` times finer than the base model's, passed through ``spflow.synthetic``'s measurement chain at the
documented noise levels (``NoiseModel()``). The base model runs the default TVD scheme on ``--cells`` cells. BCF1
and BCF2 are the calibration corefloods, BCF3 the held-out one. Cases:

* ``null`` — the truth has exactly the base model's mechanisms (the only gap is numerical);
* ``adsorption`` — polymer adsorption withheld from the base (off in the base, default strength in the truth);
* ``three`` — polymer adsorption, inaccessible pore volume and permeability reduction withheld together.

Two setups: ``sp`` (the bundled SP schedules BCF1-3, three calibrated parameters, five candidate effects) and
``polymer`` (polymer floods WF -> P -> CW with other slug sizes and concentrations, four calibrated parameters
including permeability and residual oil, seven candidate effects), the latter closer to issue 20's study.

Prints one JSON line per case (verdict, ambiguity set, final model, effects, forward runs, wall time).

    python scripts/gap_independent_world.py --cases null adsorption --seeds 1 --jobs 2
"""

from __future__ import annotations

import argparse
import json
import time

from spflow.plugins.forward.simulate import simulate
from spflow.plugins.gap.base_model import BaseModel
from spflow.plugins.gap.diagnosis import Options, diagnose
from spflow.plugins.gap.report import report_dataset, summary
from spflow.plugins.forward.schedule import as_schedule
from spflow.io.format import schedule_json
from spflow.synthetic import NoiseModel, measure

TRUTH = {"ALPHAV2": 2.4, "HBNC70": 0.03, "E1WC": 2.2, "E2WC": 2.2, "E3WC": 2.2}
PARAMETERS = {"ALPHAV2": [0.0, 3.0], "HBNC70": [0.02, 0.05],
              "n_low": {"names": ["E1WC", "E2WC", "E3WC"], "range": [1.5, 3.0]}}
CATALOGUE = ["capillary_pressure", "dispersion", "inaccessible_pore_volume", "polymer_adsorption",
             "permeability_reduction"]
POLYMER_TRUTH = {"AP1": 20.0, "E1WC": 2.2, "E2WC": 2.2, "E3WC": 2.2, "PERM": 700.0, "S2RWC": 0.3}
POLYMER_PARAMETERS = {"AP1": [5.0, 40.0], "n_low": {"names": ["E1WC", "E2WC", "E3WC"], "range": [1.5, 3.0]},
                      "PERM": {"range": [300.0, 1500.0], "scale": "log"}, "S2RWC": [0.2, 0.4]}
POLYMER_CATALOGUE = CATALOGUE + ["shear_thinning", "kinetic_adsorption"]


def _flood(polymer_pv, ppm, chase_pv):
    return as_schedule([{"name": "WF", "pv": 0.6, "salinity_ppm": 9400.0},
                        {"name": "P", "pv": polymer_pv, "salinity_ppm": 9400.0, "polymer_ppm": ppm},
                        {"name": "CW", "pv": chase_pv, "salinity_ppm": 9400.0}])


SETUPS = {  # schedules (2 calibration + 1 held out), truth, calibrated parameters, catalogue
    "sp": ({"BCF1": "BCF1", "BCF2": "BCF2", "BCF3": "BCF3"}, TRUTH, PARAMETERS, CATALOGUE),
    "polymer": ({"PF1": _flood(0.8, 1000.0, 1.0), "PF2": _flood(0.5, 1500.0, 1.2), "PF3": _flood(1.2, 800.0, 0.8)},
                POLYMER_TRUTH, POLYMER_PARAMETERS, POLYMER_CATALOGUE),
}
WITHHELD = {"null": (), "adsorption": ("polymer_adsorption",),
            "three": ("polymer_adsorption", "inaccessible_pore_volume", "permeability_reduction")}


def coreflood(name: str, schedule, truth: dict, cells: int, seed: int):
    """Lab-like data of ``schedule`` from the upwind fine-grid truth (every default effect on)."""
    sched = as_schedule(schedule)
    clean = simulate(sched, truth, cells=cells, scheme="upwind", pv_step=0.005)
    return measure(clean, NoiseModel(), seed, experiment=name, source="upwind fine-grid truth",
                   schedule=schedule_json(sched))


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--setup", default="sp", choices=sorted(SETUPS))
    p.add_argument("--cases", nargs="+", default=["null", "adsorption"], choices=sorted(WITHHELD))
    p.add_argument("--seeds", type=int, default=1)
    p.add_argument("--cells", type=int, default=30)
    p.add_argument("--refine", type=int, default=4)
    p.add_argument("--jobs", type=int, default=1)
    p.add_argument("--max-nfev", type=int, default=15)
    p.add_argument("--max-effects", type=int, default=3)
    p.add_argument("--variables", nargs="+", default=["dp", "oil_cut"])
    p.add_argument("--drop-surfactant-assay", action="store_true",
                   help="remove c_surfactant_out from the data (all zero in polymer floods; older diagnoses "
                        "aborted on it)")
    args = p.parse_args()
    parallel = None
    if args.jobs > 1:
        from joblib import Parallel

        parallel = Parallel(n_jobs=args.jobs)
    schedules, truth, parameters, catalogue = SETUPS[args.setup]
    names = list(schedules)
    for seed in range(args.seeds):
        data = {n: coreflood(n, s, truth, args.cells * args.refine, 100 * seed + k)
                for k, (n, s) in enumerate(schedules.items())}
        if args.drop_surfactant_assay:
            data = {n: ds.drop_vars("c_surfactant_out") for n, ds in data.items()}
        for case in args.cases:
            base = BaseModel.from_mapping({"cells": args.cells, "parameters": parameters,
                                           "effects": {name: 0.0 for name in WITHHELD[case]}})
            options = Options(max_nfev=args.max_nfev, replicates=50, max_effects=args.max_effects,
                              variables=tuple(args.variables))
            start = time.perf_counter()
            g = diagnose([data[names[0]], data[names[1]]], [data[names[2]]], base, catalogue, options,
                         parallel=parallel)
            s = summary(report_dataset(g))
            print(json.dumps({"setup": args.setup, "cells": args.cells, "variables": args.variables, "case": case,
                              "seed": seed, "verdict": s["verdict"],
                              "ambiguity_set": s["ambiguity_set"], "accepted_steps": s["accepted_steps"],
                              "final_model": s["final_model"],
                              "effects": s["effects"], "chi2_base": s["fit"]["chi2_base"], "dof": s["fit"]["dof"],
                              "chi2_base_measurement_only": (s.get("numerical_error") or {}).get(
                                  "chi2_base_measurement_only"),
                              "numerical_scale": ((s.get("numerical_error") or {}).get("scale") or {}).get(
                                  "estimate"),
                              "numerical_scale_interval": [((s.get("numerical_error") or {}).get("scale") or {})
                                                           .get(k) for k in ("lower", "upper")],
                              "gap_closed": s["gap_closed"], "forward_runs": s["forward_runs"],
                              "wall_time_s": round(time.perf_counter() - start, 1),
                              "tried_not_declared": s.get("tried_not_declared"), "search": s.get("search")}),
                  flush=True)


if __name__ == "__main__":
    main()
