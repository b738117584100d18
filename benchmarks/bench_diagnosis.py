"""Cost of a gap diagnosis (issue 20, item 5), a script, not a test:

    python benchmarks/bench_diagnosis.py --jobs 2            # 100 cells: the bundled data and a twin pair
    python benchmarks/bench_diagnosis.py --quick --jobs 2    # 60 cells (smoke run)
    python benchmarks/bench_diagnosis.py --jobs 2 --cases bundled --modes exact,secant   # one case, two modes

Two cases, each diagnosed in up to four modes in the same process, so the table shows them side by side:

* ``before`` -- every cost reduction off (``Options(economy=False, first_round_jacobian="difference")``);
* ``exact`` -- the exact reductions only (``economy=True``, forward-difference Jacobians in the first round of a
  multi-start fit: the default options);
* ``laplace`` -- the exact reductions with the held-out scores linearised at the optimum
  (``heldout_predictive="laplace"``, the default before stage version 13; the default's sampled posterior
  predictive costs about 2 x ``predictive_draws`` forward runs per scored model: docs/gap.md, Scores);
* ``secant`` -- the exact reductions plus Broyden (secant) Jacobians in the first round of every multi-start fit
  and a forward-difference refit of the declared final model (``first_round_jacobian="secant"``, an option that
  changes results: docs/gap.md, Cost).

The cases:

* ``bundled`` -- the ``gap_diagnosis`` pipeline's diagnosis of the bundled study (BCF1 + BCF2 calibrate, BCF3
  held out, the nine Table 3.2 parameters, every catalogue effect a candidate), default options;
* ``twin`` -- a two-coreflood study like the twin study's (``scripts/gap_validation.py``): BCF1 calibrates,
  BCF2 is held out, both made by ``spflow.synthetic.make_coreflood`` (default lab noise, seeds 5 and 6) on the
  simulator's grid from the Table 3.2 defaults with polymer adsorption doubled (withheld from the base model).

Per run it prints the forward runs, their CPU seconds, the diagnosing process's own CPU seconds and the wall
seconds of every phase of the diagnosis (:mod:`spflow.plugins.gap.cost`), the total wall and CPU seconds (this process plus its joblib workers, read from
``/proc``: on a machine shared with other jobs the wall time grows with the load, the CPU time hardly; the load
average is printed with the table), and the verdict, ambiguity set, fitted strengths and final chi2 of every mode,
with the largest difference from the first mode run (the script says whether verdict and ambiguity set are the
same).
"""

from __future__ import annotations

import argparse
import os
import resource
import time
from dataclasses import replace

import numpy as np

os.environ.setdefault("NUMBA_NUM_THREADS", "1")

from joblib import Parallel, delayed, parallel_config  # noqa: E402

from spflow.io.observed_source import load_observed  # noqa: E402
from spflow.pipelines.gap_diagnosis import pipeline  # noqa: E402
from spflow.plugins.gap.base_model import TABLE_3_2_BASE, BaseModel  # noqa: E402
from spflow.plugins.gap.cost import PHASES  # noqa: E402
from spflow.plugins.gap.diagnosis import diagnose  # noqa: E402
from spflow.plugins.gap.observed import load_experiments  # noqa: E402
from spflow.plugins.gap.prediction import measured_run  # noqa: E402
from spflow.plugins.gap.stage import Diagnose  # noqa: E402
from spflow.synthetic import NoiseModel, make_coreflood  # noqa: E402

_TICK = os.sysconf("SC_CLK_TCK")


def _cpu_seconds() -> float:
    """CPU seconds of this process, its finished children and its live descendants (the joblib workers)."""
    me = resource.getrusage(resource.RUSAGE_SELF)
    gone = resource.getrusage(resource.RUSAGE_CHILDREN)
    total = me.ru_utime + me.ru_stime + gone.ru_utime + gone.ru_stime
    parents: dict[int, int] = {}
    ticks: dict[int, int] = {}
    for entry in os.listdir("/proc"):
        if not entry.isdigit():
            continue
        try:
            with open(f"/proc/{entry}/stat") as f:
                fields = f.read().rsplit(")", 1)[1].split()
        except OSError:
            continue
        parents[int(entry)] = int(fields[1])
        ticks[int(entry)] = int(fields[11]) + int(fields[12])
    me_pid = os.getpid()
    for pid in parents:
        p = parents[pid]
        while p not in (0, 1, me_pid) and p in parents:
            p = parents[p]
        if p == me_pid and pid != me_pid:
            total += ticks[pid] / _TICK
    return total


def bundled_case(cells: int):
    """(calibration, held-out, base, options) of the gap_diagnosis pipeline on the bundled study."""
    params = pipeline(cells=cells).nodes["diagnosis"].params
    stage = Diagnose(**params)
    cal, held = ([load_observed(s) for s in params[k]] for k in ("calibration", "heldout"))
    return cal, held, stage.base_model, stage.options


def twin_case(cells: int):
    """(calibration, held-out, base, options) of a two-coreflood twin with doubled polymer adsorption."""
    base = BaseModel.from_mapping(TABLE_3_2_BASE | {"cells": cells})
    truth = base.forward_params(base.values(base.default_unit()))
    data = [make_coreflood(s, truth, effects={"polymer_adsorption": 2.0}, noise=NoiseModel(), seed=5 + k,
                           cells=cells) for k, s in enumerate(("BCF1", "BCF2"))]
    stage = Diagnose(calibration=[], heldout=[], base=TABLE_3_2_BASE | {"cells": cells})
    return [data[0]], [data[1]], base, stage.options


#: mode -> the options it replaces
MODES = {"before": {"economy": False, "first_round_jacobian": "difference"},
         "exact": {"economy": True, "first_round_jacobian": "difference"},
         "laplace": {"economy": True, "first_round_jacobian": "difference", "heldout_predictive": "laplace"},
         "secant": {"economy": True, "first_round_jacobian": "secant"}}


def run(case: str, cells: int, mode: str, parallel) -> dict:
    cal, held, base, options = (bundled_case if case == "bundled" else twin_case)(cells)
    options = replace(options, **MODES[mode])
    cpu, wall = _cpu_seconds(), time.perf_counter()
    g = diagnose(cal, held, base, None, options, parallel=parallel)
    wall, cpu = time.perf_counter() - wall, _cpu_seconds() - cpu
    return {"case": case, "cells": cells, "mode": mode, "cost": g.cost,
            "runs": g.forward_runs, "wall": wall, "cpu": cpu, "verdict": g.verdict, "ambiguity": g.ambiguity,
            "strengths": g.final_fit.strengths, "chi2": g.final_fit.chi2,
            "tried": {k: v for k, v in g.tried.items()}}


def _table(rows: list[dict]) -> list[str]:
    """Markdown table: per run, forward runs (and their CPU s per run) of every phase, totals, verdict."""
    phases = [p for p in PHASES if any(p in r["cost"] for r in rows)]
    head = ["case", "cells", "mode"] + phases + ["runs", "run CPU s", "wall s", "CPU s", "verdict", "final χ²"]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for r in rows:
        cells = [r["case"], str(r["cells"]), r["mode"]]
        for p in phases:
            c = r["cost"].get(p)
            cells.append("-" if c is None else f"{c.runs} ({c.run_cpu_s / c.runs:.2f} s)" if c.runs
                         else f"0 ({c.own_cpu_s:.0f} s own)")
        cells += [str(r["runs"]), f"{sum(c.run_cpu_s for c in r['cost'].values()):.0f}", f"{r['wall']:.0f}",
                  f"{r['cpu']:.0f}", f"{r['verdict']} {r['ambiguity']}", f"{r['chi2']:.1f}"]
        lines.append("| " + " | ".join(cells) + " |")
    return lines


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="60 cells instead of 100")
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--cases", default="bundled,twin", help="comma-separated: bundled, twin")
    ap.add_argument("--modes", default="before,exact,secant", help=f"comma-separated: {', '.join(MODES)}")
    args = ap.parse_args()
    unknown = sorted(set(args.modes.split(",")) - set(MODES))
    if unknown:
        ap.error(f"unknown modes {unknown}; allowed {list(MODES)}")
    cells = 60 if args.quick else 100
    with parallel_config(backend="loky", inner_max_num_threads=1):
        parallel = Parallel(n_jobs=args.jobs) if args.jobs > 1 else None
    if parallel is not None:  # load the compiled kernel in every worker before anything is timed
        base = BaseModel.from_mapping(TABLE_3_2_BASE | {"cells": cells})
        cal, *_ = bundled_case(cells)
        exp = load_experiments(cal[:1], 0.1, base.schedules)[0]
        params, effects = base.forward_params(base.values(base.default_unit())), base.effects
        parallel(delayed(measured_run)(exp, params, effects, cells) for _ in range(4 * args.jobs))
    rows = []
    for case in args.cases.split(","):
        for mode in args.modes.split(","):
            r = run(case, cells, mode, parallel)
            rows.append(r)
            phases = ", ".join(f"{p} {c.runs} runs ({c.run_cpu_s:.1f} CPU s) + {c.own_cpu_s:.1f} CPU s own, "
                               f"{c.wall_s:.0f} s wall" for p, c in r["cost"].items())
            print(f"{case} {mode}: {r['runs']} runs, wall {r['wall']:.0f} s, CPU {r['cpu']:.0f} s (parallel "
                  f"efficiency CPU / (jobs x wall) {r['cpu'] / (args.jobs * r['wall']):.2f}); {phases}; "
                  f"verdict {r['verdict']} {r['ambiguity']}, strengths {r['strengths']}, final chi2 {r['chi2']:.3f}",
                  flush=True)
    print(f"\nload average {os.getloadavg()[0]:.1f} (2 cores shared with other jobs), jobs {args.jobs}")
    print("\n".join(_table(rows)))
    for case in args.cases.split(","):
        a, *others = [r for r in rows if r["case"] == case]
        for b in others:
            same = a["verdict"] == b["verdict"] and a["ambiguity"] == b["ambiguity"]
            diff = max([abs(a["strengths"][k] - b["strengths"].get(k, np.nan)) / abs(a["strengths"][k])
                        for k in a["strengths"]] + [0.0])
            tried = max([abs(a["tried"][k] - b["tried"].get(k, np.nan)) / abs(a["tried"][k]) for k in a["tried"]]
                        + [0.0])
            print(f"{case} {a['mode']} -> {b['mode']}: verdict and ambiguity set {'identical' if same else 'DIFFER'}; "
                  f"largest relative strength difference {diff:.3g} (final model), {tried:.3g} (tried effects); "
                  f"chi2 {a['chi2']:.3f} / {b['chi2']:.3f}; strengths {a['strengths']} / {b['strengths']}, tried "
                  f"{a['tried']} / {b['tried']}")


if __name__ == "__main__":
    main()
