"""Kriging benchmark (a script, not a test): ``python benchmarks/bench_kriging.py [--samples 200] [--jobs 2]``.

Question: how expensive is a Kriging proxy to evaluate -- the calibration calls it 10^4-10^5 times -- and what does
sharing length scales across the outputs of a QoI (``share="variable"``) buy against one Kriging model per output
(``share="output"``, UQLab's and the thesis's choice)?

Setting: thesis §3.8 -- BCF1, the 9 parameters of Table 3.2, N_s = 200 LHS training runs, Δp and recovery on the
0.1 PV grid (2 x 44 outputs). The training and validation runs and the fits come from the spflow pipeline of
``benchmarks/figures/fig_3_15_pck_band.py`` (shared cache). For PC-Kriging (sequential) and the plain GP, each with
both sharing rules, the table reports

* fit time (wall, ``--jobs`` workers; only for fits made in this run -- cached fits show "cached");
* prediction time of mean + variance at 10^4 points, and per call for batches of 1, 32 and 120 points (one
  emcee walker, a walker ensemble, an NSGA-II population), BLAS limited to one thread;
* the ratio to the sparse PCE's prediction time measured in the same run (the baseline), and the time of one
  forward-model run for scale;
* validation error ε_val^mean per QoI (Eq. 3.8 on ``--validation`` independent LHS runs, averaged over PV, Eq. 3.9;
  see ``validation_scores`` of the figure script) and the fraction of validation values inside the ±2σ band.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

import numpy as np
from threadpoolctl import threadpool_limits

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "benchmarks" / "figures"))

import spflow  # noqa: E402
from fig_3_15_pck_band import QOIS, pipeline, validation_scores  # noqa: E402
from spflow.plugins.forward.simulate import simulate  # noqa: E402
from spflow.plugins.surrogates.contract import load_surrogate  # noqa: E402
from spflow.plugins.surrogates.training_data import training_set  # noqa: E402

PROXIES = {
    "pck": ("pck", {"mode": "sequential", "degree_max": 3}),
    "pck_var": ("pck", {"mode": "sequential", "degree_max": 3, "share": "variable"}),
    "gp": ("gp", {}),
    "gp_var": ("gp", {"share": "variable"}),
    "pce": ("pce", {"solver": "lars", "degree_max": 5}),
}


def timed(fn, repeat: int) -> float:
    """Median wall time of ``fn()`` over ``repeat`` calls (after one warm-up call)."""
    fn()
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, default=200)
    parser.add_argument("--validation", type=int, default=200)
    parser.add_argument("--cells", type=int, default=100)
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--points", type=int, default=10_000)
    parser.add_argument("--cache", type=Path, default=ROOT / ".spflow")
    parser.add_argument("--refit", action="store_true",
                        help="refit the proxies even if cached (the cache fingerprints stage classes, not helpers)")
    args = parser.parse_args(argv)

    p = pipeline(args.samples, args.validation, args.cells, PROXIES)
    spflow.run(p, cache=args.cache, jobs=args.jobs, until=["runs_train", "runs_val"])  # the simulations
    fit_times = {}
    for node in PROXIES:  # one node at a time, to time each fit on its own
        start = time.perf_counter()
        result = spflow.run(p, cache=args.cache, jobs=args.jobs, until=[node], force=[node] if args.refit else (),
                            verbose=False)
        fit_times[node] = time.perf_counter() - start if node in result.executed else None
    result = spflow.run(p, cache=args.cache, jobs=args.jobs, verbose=False)
    models = {name: load_surrogate(result[name]) for name in PROXIES}
    val = training_set(result["space"], result["design_val"], result["runs_val"], [q for q, _, _ in QOIS], ["BCF1"])
    space = result["space"]
    lower, upper = space["lower"].values, space["upper"].values
    x = lower + (upper - lower) * np.random.default_rng(0).uniform(size=(args.points, lower.size))
    names = [str(n) for n in space["param"].values]
    forward = timed(lambda: simulate("BCF1", dict(zip(names, x[0])), cells=args.cells, pv_step=0.1), 5)

    with threadpool_limits(limits=1, user_api="blas"):
        big = {name: timed(lambda m=m: m.predict(x), 3) for name, m in models.items()}
        batches = {name: [timed(lambda m=m, b=b: m.predict(x[:b]), 20) for b in (1, 32, 120)]
                   for name, m in models.items()}
    base = big["pce"]
    print(f"BCF1, {lower.size} parameters, N_s = {args.samples}, {len(models['pck'].outputs)} outputs; "
          f"one forward run: {forward * 1e3:.1f} ms; BLAS 1 thread")
    print(f"{'proxy':>8} {'groups':>6} {'fit s':>7} {'10^4 pts s':>10} {'x PCE':>6} {'b=1 ms':>7} {'b=32 ms':>8} "
          f"{'b=120 ms':>9} {'eps_val dp':>10} {'eps_val rec':>11} {'2σ cover':>8}")
    for name, model in models.items():
        fit = "cached" if fit_times[name] is None else f"{fit_times[name]:.0f}"
        groups = model.lengthscale.shape[0] if hasattr(model, "lengthscale") else "-"
        score = validation_scores(model, val)
        cover = np.mean([c for _, c in score.values()])
        b1, b32, b120 = (t * 1e3 for t in batches[name])
        scale = args.points / 10_000
        print(f"{name:>8} {groups!s:>6} {fit:>7} {big[name] / scale:10.3f} {big[name] / base:6.1f} {b1:7.2f} "
              f"{b32:8.2f} {b120:9.2f} {score['dp'][0]:10.2e} {score['recovery'][0]:11.2e} {cover:8.3f}")
    print(f"(forward model at 10^4 points, serial: {forward * 1e4:.0f} s)")


if __name__ == "__main__":
    main()
