"""Stress benchmark of the 1-D forward model (a script, not a test): ``python benchmarks/bench_stress.py [-n 10000]``.

Runs ``N`` random in-bounds draws -- every forward-model parameter inside its declared bounds
(``parameters.PARAMETERS``) and every effect strength inside its bounds (``effects.BUILTIN_EFFECTS``), a random
schedule of BCF1-3 and a random grid of 30-100 cells -- with the default step and wall-time budgets, and reports:

- failed runs by reason (a ``SimulationError``: budget exhausted, time-step collapse, ...);
- NaN/inf values in the series and in the final profiles;
- bound violations: saturations outside [0, 1], negative concentrations, oil cut outside [0, 1], recovery outside
  [0, 1], decreasing recovery (all with a 1e-9 round-off allowance);
- the largest per-component relative mass-balance error;
- steps and wall times: median, the slowest run's time as a multiple of the median, the largest steps as a multiple
  of the run's expected steps (``budgets.expected_steps``);
- the slowest draws with the step-control counts (``n_halvings``, ``n_capillary_limited``, ``n_ramp_limited``) and
  the parameters that set them apart, to say which mechanism limits their steps.
- the runs in which the budgeted mode (``--capillary``, default simulate's ``budgeted``) left the explicit scheme
  past half the step budget: the implicit capillary step (``capillary_implicit_from_pv``) and the implicit release of
  a phase near its residual (``n_oil_release_implicit`` for oil, ``n_non_oleic_release_implicit`` for the aqueous or
  microemulsion phase).

Draws: a parameter whose positive range spans more than two decades is drawn log-uniformly, one in [0, upper] with
``upper >= 100`` is 0 with probability 0.2 and else log-uniform in [1e-4 upper, upper], others uniformly; integer
flags uniformly;
the cross-parameter rules (``resolve_params``) by construction: the three low-Nc residuals redrawn until their sum
is < 1, each high-Nc residual uniform in [0, its low-Nc one], CSEL/CSEU sorted, F6S uniform in [0, min(1, 1/BETA6)),
``SWI`` uniform in [``S1RWC``, 1].
Effect strengths are drawn the same way. A case whose injected-fluid viscosity exceeds the physical cap
(``injected_viscosity_cap``: ``simulate`` rejects it with a ``ParameterError``) is redrawn whole, and the redraws are
counted (``--no-cap`` keeps every draw: the draws of the issue-22 runs before the cap, whose numbers
docs/forward_model.md quotes). Draw ``k`` is the ``k``-th case of the seeded stream; ``--draws 107,124`` runs only
those (with ``--max-steps F``: a step budget of ``F`` times the expected steps, so an over-budget draw stops in
seconds). ``--save FILE`` writes every run as it finishes; ``--resume`` continues an interrupted run from that file.
Runs go through joblib (``--jobs``, default 2 workers).
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import time

import numpy as np

os.environ.setdefault("NUMBA_NUM_THREADS", "1")

from joblib import Parallel, delayed  # noqa: E402

from spflow.core.errors import ParameterError  # noqa: E402
from spflow.plugins.forward.budgets import expected_steps  # noqa: E402
from spflow.plugins.forward.effects import BUILTIN_EFFECTS, default_registry  # noqa: E402
from spflow.plugins.forward.errors import SimulationError  # noqa: E402
from spflow.plugins.forward.parameters import PARAMETERS, resolve_params  # noqa: E402
from spflow.plugins.forward.injected_viscosity_cap import (  # noqa: E402
    check_injected_viscosity, peak_injected_viscosity)
from spflow.plugins.forward.run_arguments import CAPILLARY, DEFAULT_CAPILLARY  # noqa: E402
from spflow.plugins.forward.schedule import BCF_SCHEDULES  # noqa: E402
from spflow.plugins.forward.simulate import simulate  # noqa: E402

SCHEDULES = ("BCF1", "BCF2", "BCF3")
TOL = 1.0e-9


def _draw(rng, lower, upper, integer=False):
    if integer:
        return float(rng.integers(int(lower), int(upper) + 1))
    if upper <= lower:
        return float(lower)
    if lower > 0.0 and upper / lower > 100.0:
        return float(np.exp(rng.uniform(np.log(lower), np.log(upper))))
    if lower == 0.0 and upper >= 100.0:
        if rng.random() < 0.2:
            return 0.0
        return float(np.exp(rng.uniform(np.log(1.0e-4 * upper), np.log(upper))))
    return float(rng.uniform(lower, upper))


def draw_case(rng, cap: bool = True) -> tuple[dict, int]:
    """One in-bounds case ``{"schedule", "cells", "params", "effects"}`` and the number of cases rejected before it
    by the injected-viscosity cap (redrawn; none with ``cap=False``)."""
    registry = default_registry()
    rejected = 0
    while True:
        case = _draw_once(rng)
        if not cap:
            return case, rejected
        try:
            check_injected_viscosity(resolve_params(case["params"]), registry.resolve(case["effects"]),
                                    BCF_SCHEDULES[case["schedule"]])
        except ParameterError:
            rejected += 1
            continue
        return case, rejected


def _draw_once(rng) -> dict:
    """One case inside the bounds and the cross-parameter rules of ``resolve_params``."""
    params = {s.name: _draw(rng, s.lower, s.upper, s.integer) for s in PARAMETERS}
    spec = {s.name: s for s in PARAMETERS}
    while params["S1RWC"] + params["S2RWC"] + params["S3RWC"] >= 1.0:  # residuals leave a mobile window
        for name in ("S1RWC", "S2RWC", "S3RWC"):
            params[name] = _draw(rng, spec[name].lower, spec[name].upper)
    for high, low in (("S1RC", "S1RWC"), ("S2RC", "S2RWC"), ("S3RC", "S3RWC")):
        params[high] = float(rng.uniform(0.0, params[low]))
    params["CSEL"], params["CSEU"] = sorted((params["CSEL"], params["CSEU"]))
    params["F6S"] = float(rng.uniform(0.0, min(1.0, 0.999 / params["BETA6"]) if params["BETA6"] > 0 else 1.0))
    params["SWI"] = float(rng.uniform(params["S1RWC"], 1.0))
    resolve_params(params)  # every rule holds by construction; this raises if one does not
    effects = {e.name: _draw(rng, e.lower, e.upper) for e in BUILTIN_EFFECTS}
    return {"schedule": str(rng.choice(SCHEDULES)), "cells": int(rng.integers(30, 101)), "params": params,
            "effects": effects}


def capillary_scale(case: dict) -> float:
    """``D_pc = k p_c0 / (mu_w u L)`` (PV units): the capillary diffusivity scale of a case (0 with Pc off); the
    explicit capillary step is ``dx^2 / (2 D)``, so the steps grow with ``D_pc * cells^2``."""
    p = case["params"]
    pc0 = p["CPC0"] * case["effects"]["capillary_pressure"]
    area = np.pi * p["DIAMETER"] ** 2 / 4.0
    u = p["QINJ"] * 1.0e-6 / 60.0 / area
    return p["PERM"] * 9.869233e-16 * pc0 / (p["VIS1"] * 1.0e-3 * u * p["LENGTH"])


def injected_peak(case: dict) -> float:
    """The case's largest injected-fluid viscosity (cP, ``injected_viscosity_cap``)."""
    return peak_injected_viscosity(resolve_params(case["params"]), default_registry().resolve(case["effects"]),
                                  BCF_SCHEDULES[case["schedule"]])[0]


def run_case(case: dict, max_wall_s: float | None = None, capillary: str = DEFAULT_CAPILLARY,
             max_steps_factor: float | None = None) -> dict:
    """Run one case; returns the measures of the module docstring (``failure``: the reason, or ``""``).
    ``max_steps_factor``: a step budget of that many times the expected steps (default: simulate's)."""
    total = BCF_SCHEDULES[case["schedule"]].total_pv
    out = {"schedule": case["schedule"], "cells": case["cells"], "expected": expected_steps(total, case["cells"], 0.5)}
    max_steps = None if max_steps_factor is None else max(1, int(max_steps_factor * out["expected"]))
    cpu0, start = time.process_time(), time.perf_counter()
    try:
        ds = simulate(case["schedule"], case["params"], cells=case["cells"], effects=case["effects"], pv_step=0.01,
                      profiles_at=[total], max_wall_s=max_wall_s, capillary=capillary, max_steps=max_steps)
    except SimulationError as err:
        out.update(failure=err.reason, pv=err.pv, cell=err.cell, wall=time.perf_counter() - start,
                   cpu=time.process_time() - cpu0, steps=-1)
        return out
    except ParameterError as err:  # only with --no-cap: simulate rejects the case before any work
        out.update(failure=f"rejected before any work: {err}", wall=time.perf_counter() - start,
                   cpu=time.process_time() - cpu0, steps=-1)
        return out
    wall, cpu = time.perf_counter() - start, time.process_time() - cpu0
    values = [ds[v].values for v in ds.data_vars]
    nonfinite = int(sum(np.count_nonzero(~np.isfinite(v)) for v in values))
    viol = 0
    for v in ("sw", "so", "sme"):
        viol += int(np.count_nonzero((ds[v].values < -TOL) | (ds[v].values > 1.0 + TOL)))
    for v in ("c_polymer", "c_surfactant", "salinity", "c_polymer_out", "c_surfactant_out", "salinity_out"):
        viol += int(np.count_nonzero(ds[v].values < -TOL))
    for v in ("oil_cut", "recovery"):
        viol += int(np.count_nonzero((ds[v].values < -TOL) | (ds[v].values > 1.0 + TOL)))
    viol += int(np.count_nonzero(np.diff(ds["recovery"].values) < -TOL))
    switch = float(ds.attrs["capillary_implicit_from_pv"])
    balance = max(abs(float(v)) for k, v in ds.attrs.items() if k.startswith("mass_balance_error_"))
    out.update(failure="", wall=wall, cpu=cpu, steps=int(ds.attrs["n_steps"]), nonfinite=nonfinite, violations=viol,
               balance=balance, halvings=int(ds.attrs["n_halvings"]), capillary=int(ds.attrs["n_capillary_limited"]),
               ramp=int(ds.attrs["n_ramp_limited"]), implicit=int(ds.attrs["n_capillary_implicit"]),
               switch_pv=None if np.isnan(switch) else switch, release=int(ds.attrs["n_oil_release_implicit"]),
               release_non_oleic=int(ds.attrs["n_non_oleic_release_implicit"]))
    return out


def load_saved(path: str, cases: list[dict]) -> dict[int, dict]:
    """The runs saved in ``path`` (``--save``), by draw index, checked against this seed's ``cases``. A last line
    cut short by an interrupted write is dropped from the file (that draw runs again); any other unreadable line, or
    a draw that differs from this seed/N, stops with a message naming the file and the line."""
    with open(path) as fh:
        lines = fh.readlines()
    if lines and not lines[-1].endswith("\n"):
        print(f"{path}: dropping its last line, cut short by the interrupted run ({len(lines[-1])} characters)")
        lines = lines[:-1]
        with open(path, "w") as fh:
            fh.writelines(lines)
    done = {}
    for number, line in enumerate(lines, start=1):
        try:
            row = json.loads(line)
            index, case, result = int(row["index"]), row["case"], row["result"]
        except (ValueError, KeyError, TypeError) as err:
            raise SystemExit(f"{path}, line {number}: not a saved run ({err}); not resuming") from None
        if not 0 <= index < len(cases) or case != cases[index]:
            raise SystemExit(f"{path}, line {number}: draw {index} is not draw {index} of this seed and N "
                             f"({len(cases)} draws); not resuming")
        done[index] = result
    return done


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("-n", type=int, default=10000, help="number of draws")
    parser.add_argument("--seed", type=int, default=20261126)
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--slowest", type=int, default=10, help="slowest draws to list")
    parser.add_argument("--max-wall", type=float, help="wall-time budget per run (s; default: simulate's)")
    parser.add_argument("--save", help="write every case and result as JSON lines to this file")
    parser.add_argument("--capillary", choices=list(CAPILLARY), default=DEFAULT_CAPILLARY,
                        help="time discretisation of the capillary flux (simulate's option)")
    parser.add_argument("--no-cap", action="store_true",
                        help="keep draws above the injected-viscosity cap (the draws of the runs before the cap)")
    parser.add_argument("--draws", help="comma-separated draw indices to run (default: all N)")
    parser.add_argument("--max-steps", type=float, help="step budget as a multiple of the expected steps")
    parser.add_argument("--resume", action="store_true",
                        help="with --save: keep the runs already in that file (same seed and N) and run the rest")
    args = parser.parse_args()
    if args.resume and not args.save:
        parser.error("--resume needs --save FILE")
    rng = np.random.default_rng(args.seed)
    drawn = [draw_case(rng, cap=not args.no_cap) for _ in range(args.n)]
    cases = [case for case, _ in drawn]
    rejected = sum(r for _, r in drawn)
    indices = [int(k) for k in args.draws.split(",")] if args.draws else list(range(args.n))
    done = load_saved(args.save, cases) if args.resume and os.path.exists(args.save) else {}
    if args.resume:
        print(f"resuming: {len(done)} runs already in {args.save}")
    todo = [k for k in indices if k not in done]
    simulate("BCF1", cells=30)  # compile / load the cached kernel
    start = time.perf_counter()
    with open(args.save or os.devnull, "a" if args.resume else "w") as fh:  # one JSON line per run as it finishes
        for i, r in zip(todo, Parallel(n_jobs=args.jobs, return_as="generator")(
                delayed(run_case)(cases[k], args.max_wall, args.capillary, args.max_steps) for k in todo)):
            done[i] = r
            fh.write(json.dumps({"index": i, "case": cases[i], "result": r}) + "\n")
            fh.flush()
    results = [done[k] for k in indices]
    cases = [cases[k] for k in indices]
    elapsed = time.perf_counter() - start
    ok = [r for r in results if not r["failure"]]
    failed = [r for r in results if r["failure"]]
    reasons: dict[str, int] = {}
    for r in failed:  # by kind, without the budget value
        kind = r["failure"].split(" [")[0].split(": injected-fluid viscosity")[0]
        reasons[kind] = reasons.get(kind, 0) + 1
    walls = [r["wall"] for r in results]
    median = statistics.median(walls)
    print(f"{len(indices)} draws (BCF1-3, 30-100 cells, parameters and effects in bounds), {args.jobs} workers, "
          f"{elapsed:.0f} s, load average {os.getloadavg()[0]:.1f}")
    print(f"{'draws rejected by the viscosity cap':40s} {rejected} (redrawn; {args.n} kept)"
          if not args.no_cap else f"{'viscosity cap':40s} off (--no-cap)")
    print(f"{'finished runs':40s} {len(ok)}")
    print(f"{'failed runs (SimulationError, rejected)':40s} {len(failed)}")
    for reason, count in sorted(reasons.items(), key=lambda kv: -kv[1]):
        print(f"    {count:6d}  {reason}")
    print(f"{'NaN/inf values':40s} {sum(r['nonfinite'] for r in ok)}")
    print(f"{'bound violations':40s} {sum(r['violations'] for r in ok)}")
    print(f"{'max relative mass-balance error':40s} {max((r['balance'] for r in ok), default=float('nan')):.2e}")
    print(f"{'runs beyond the budget':40s} {sum('budget' in r['failure'] for r in failed)}")
    if ok:
        print(f"{'median steps / expected':40s} {statistics.median(r['steps'] / r['expected'] for r in ok):.3f}")
        print(f"{'max steps / expected':40s} {max(r['steps'] / r['expected'] for r in ok):.2f}")
    print(f"{'median wall time (s)':40s} {median:.4f}")
    print(f"{'slowest run wall time / median':40s} {max(walls) / median:.1f}")
    print(f"{'runs with halvings':40s} {sum(r['halvings'] > 0 for r in ok)}")
    print(f"{'runs mostly capillary-limited':40s} {sum(r['capillary'] > r['steps'] / 2 for r in ok)}")
    switched = [r for r in ok if r.get("switch_pv") is not None]
    print(f"{'runs switched to implicit Pc (budgeted)':40s} {len(switched)}"
          + (f" (max steps / expected among them {max(r['steps'] / r['expected'] for r in switched):.2f})"
             if switched else ""))
    released = [r for r in ok if r.get("release", 0) + r.get("release_non_oleic", 0) > 0]
    print(f"{'runs with the implicit release':40s} {len(released)}"
          + (f" (max steps / expected among them {max(r['steps'] / r['expected'] for r in released):.2f})"
             if released else ""))
    print(f"{'  of them with a non-oleic release':40s} {sum(r.get('release_non_oleic', 0) > 0 for r in released)}")
    order = sorted(range(len(results)), key=lambda i: -results[i]["wall"])[: args.slowest]
    print("slowest draws: index, schedule, cells, steps / expected, halvings, capillary-limited steps, ramp-limited "
          "steps, wall s, capillary diffusivity scale D_pc, VIS2/VIS1, peak injected viscosity cP, failure")
    for i in order:
        r = results[i]
        ratio = f"{r['steps'] / r['expected']:8.2f}" if r["steps"] > 0 else "       -"
        print(f"  {indices[i]:6d} {r['schedule']} {r['cells']:4d} {ratio} {r.get('halvings', -1):8d}"
              f" {r.get('capillary', -1):8d} {r.get('ramp', -1):6d} {r['wall']:8.2f}"
              f" {capillary_scale(cases[i]):9.3g} {cases[i]['params']['VIS2'] / cases[i]['params']['VIS1']:9.3g}"
              f" {injected_peak(cases[i]):9.3g} {r['failure'][:160]}")


if __name__ == "__main__":
    main()
