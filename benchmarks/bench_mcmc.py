"""MCMC benchmark (a script, not a test): ``python benchmarks/bench_mcmc.py [--steps 100000]``.

Times 10^5 MCMC steps (posterior evaluations) on one core with a PCE likelihood of the chapter-4 size: a 9-parameter
PCE (spflow's ``pce`` kind, q = 0.9, fitted by OLS to a smooth synthetic response) predicting pressure drop and oil
cut of BCF1 on the 0.1 PV grid (43 + 43 outputs), the bundled BCF1 observations, and the likelihood of §4.6 — Jeffreys
noise integrated out, with (quadrature) and without (closed form) the PCE's error variance. Each sampler makes
``--steps`` evaluations in all: emcee one run of 18 walkers (steps/18 iterations), MH one chain of ``--steps`` steps
or, as in the pipeline, 4 chains in lockstep of steps/4 each (one likelihood call per step for all four). The
baseline, measured in the same run, is the simulator itself (``spflow.simulate("BCF1")``, 100 cells): the time the
same number of posterior evaluations would take on the forward model instead of the proxy. Target (issue 7): <= 30 s
per 10^5 steps.

Two more rows split a single-chain MH step into its parts: the likelihood alone (``PosteriorModel.evaluate`` of one
point per call, as an MH chain calls it) and emcee's own per-iteration machinery (its ``MHMove`` loop with one
walker on a trivial log-probability), both per call, scaled to ``--steps`` calls.
"""

from __future__ import annotations

import argparse
import os
import statistics
import time

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("NUMBA_NUM_THREADS", "1")

import emcee  # noqa: E402
import numpy as np  # noqa: E402

from spflow.core.stage import StageContext  # noqa: E402
from spflow.plugins.calibration.emcee_sampler import EmceeSampler  # noqa: E402
from spflow.plugins.calibration.mh_sampler import GaussianProposal, MHSampler  # noqa: E402
from spflow.plugins.surrogates.contract import load_surrogate  # noqa: E402
from spflow.plugins.design.parameter_space import ParameterSpace  # noqa: E402
from spflow.plugins.design.thesis_tables import TABLE_4_1  # noqa: E402
from spflow.plugins.forward.simulate import simulate  # noqa: E402
from spflow.plugins.observations import Observations  # noqa: E402
from spflow.plugins.surrogates.basis import design_matrix, multi_indices  # noqa: E402
from spflow.plugins.surrogates.outputs import stack_outputs  # noqa: E402
from spflow.plugins.surrogates.pce_model import PCE  # noqa: E402



def synthetic_pce(space, degree: int, rng: np.random.Generator) -> PCE:
    """A 9-D PCE of the chapter-4 shape: the outputs of one BCF1 simulation times 1 + a random polynomial of total
    degree ``degree`` in θ (so the degree-adaptive fit keeps every degree up to it), plus small noise."""
    base = simulate("BCF1", cells=100, pv_step=0.1).expand_dims(sample=[0], experiment=["BCF1"])
    y0, index = stack_outputs(base, ["dp", "oil_cut"], ["BCF1"])
    lower, upper = space["lower"].values, space["upper"].values
    n = 800
    x = rng.uniform(lower, upper, size=(n, lower.size))
    z = 2 * (x - lower) / (upper - lower) - 1
    psi = design_matrix(z, multi_indices(lower.size, degree, 0.9))
    shape = 1 + 0.3 * psi[:, 1:] @ rng.normal(size=(psi.shape[1] - 1, y0.shape[1])) / np.sqrt(psi.shape[1])
    y = y0 * shape + 1e-3 * np.abs(y0).max(axis=0) * rng.normal(size=(n, y0.shape[1]))
    return PCE.fit([str(p) for p in space["param"].values], lower, upper, index, x, y, degree_max=degree, q=0.9,
                   solver="ols")


def time_sampler(stage, surrogate, observations, space) -> float:
    start = time.perf_counter()
    stage.run(StageContext("bench", n_jobs=1, verbose=False), surrogate=surrogate, observations=observations,
              space=space)
    return time.perf_counter() - start


def time_likelihood(stage, surrogate, observations, space, calls: int) -> float:
    """Seconds for ``calls`` one-point evaluations of the stage's posterior at uniform points of the box."""
    model = stage.model(load_surrogate(surrogate), observations, space)
    points = np.random.default_rng(0).uniform(model.lower, model.upper, size=(calls, model.n_theta))[:, None, :]
    start = time.perf_counter()
    for x in points:
        model(x)
    return time.perf_counter() - start


def time_emcee_loop(iterations: int, ndim: int = 9) -> float:
    """Seconds for ``iterations`` of emcee's MHMove loop, one walker, log-probability and blob of a few flops."""
    def log_prob(x):
        return np.column_stack([-0.5 * np.sum(x * x, axis=1), np.zeros(len(x))])

    sampler = emcee.EnsembleSampler(1, ndim, log_prob, moves=emcee.moves.MHMove(GaussianProposal(0.1 * np.eye(
        ndim)[None])), vectorize=True, blobs_dtype=float)
    start = time.perf_counter()
    sampler.run_mcmc(np.zeros((1, ndim)), iterations, skip_initial_state_check=True)
    return time.perf_counter() - start


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--steps", type=int, default=100_000)
    parser.add_argument("--degrees", type=int, nargs="+", default=[3, 4])
    parser.add_argument("--sim-runs", type=int, default=10)
    args = parser.parse_args()
    ctx = StageContext("bench", verbose=False)
    space = ParameterSpace(names=list(TABLE_4_1), ranges=TABLE_4_1).run(ctx)
    observations = Observations(experiments=["BCF1"]).run(ctx)
    simulate("BCF1", cells=100)  # compile / load the kernel
    sim = []
    for _ in range(args.sim_runs):
        start = time.perf_counter()
        simulate("BCF1", cells=100)
        sim.append(time.perf_counter() - start)
    per_sim = statistics.median(sim)
    steps = args.steps
    budget = {"samples": steps, "burn": steps // 5, "thin": 5, "chains": 1, "seed": 1}
    four = dict(budget, samples=steps // 4, burn=steps // 20, chains=4)  # 4 chains sharing the steps
    rows = []
    for degree in args.degrees:
        pce = synthetic_pce(space, degree, np.random.default_rng(degree))
        surrogate = pce.to_dataset()
        for label, stage in (
            ("emcee, marginal + PCE variance", EmceeSampler(**budget)),
            ("emcee, marginal (closed form)", EmceeSampler(surrogate_variance=False, **budget)),
            ("MH 1 chain, marginal + PCE variance", MHSampler(**budget)),
            ("MH 4 chains, marginal + PCE variance", MHSampler(**four)),
        ):
            seconds = time_sampler(stage, surrogate, observations, space)
            rows.append((f"P={pce.indices.shape[0]:>3} {label}", seconds, steps / seconds, steps * per_sim / seconds))
        calls = max(steps // 10, 1)
        seconds = time_likelihood(MHSampler(**budget), surrogate, observations, space, calls) * steps / calls
        rows.append((f"P={pce.indices.shape[0]:>3} likelihood alone, 1 point per call", seconds, steps / seconds,
                     steps * per_sim / seconds))
    calls = max(steps // 10, 1)
    seconds = time_emcee_loop(calls) * steps / calls
    rows.append(("emcee MHMove loop alone, 1 walker", seconds, steps / seconds, steps * per_sim / seconds))
    print(f"{steps} MCMC steps (posterior evaluations), one core; simulator BCF1 at 100 cells: "
          f"{1e3 * per_sim:.1f} ms per run (median of {args.sim_runs})")
    print(f"{'configuration':<46} {'seconds':>8} {'steps/s':>10} {'x faster than simulator':>24}  target <= 30 s")
    for label, seconds, rate, ratio in rows:
        print(f"{label:<46} {seconds:8.1f} {rate:10.0f} {ratio:24.0f}  {'ok' if seconds <= 30 else 'MISSED'}")


if __name__ == "__main__":
    main()
