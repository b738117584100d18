"""How much dispersion OPM Flow's own numerics put into the independent-world data (issue 20), against the
dispersion the gap diagnosis names on those data when its base model has none.

The independent-world study (``scripts/independent_world.py``, docs/gap.md "Independent world") runs the null case
-- the truth has no physical dispersion -- through OPM Flow on 100 cells. OPM discretises the polymer transport
fully implicitly in time and first-order upwind in space, which smears a concentration front like a physical
longitudinal dispersivity of (Lantz 1971, "Quantitative evaluation of numerical diffusion (truncation error)",
SPE Journal 11(3) 315-320; the implicit-in-time, upstream-in-space case)

    alpha_num = dx/2 * (1 + nu),     nu = v dt / dx   (the front's Courant number),

with ``dx`` the cell length, ``dt`` OPM's time step and ``v`` the front's speed. This script measures every input
of that formula on OPM's own run of each schedule of the null case, independently of spflow's forward model:

* ``dt`` from OPM's ``.INFOSTEP`` file (the steps its solver actually took while the polymer front crossed the
  core), converted to pore volumes with the deck's time per pore volume;
* ``v`` from OPM's effluent polymer: the front crosses the core (one core length) between the start of the polymer
  slug and the effluent's reaching half the injected concentration, so ``v = 1 / (that time in PV)`` core lengths
  per PV, and ``dx`` = 1 / cells core lengths;

and prints ``alpha_num`` in ft next to the dispersivity the diagnosis fitted on the same data (the records of the
study, ``docs/independent_world_v3.json``: the ``dispersion`` effect's strength times the base's ``ALPHAL`` of
0.01 ft). OPM takes its own time steps here (``max_step_pv=None``), as it did for those data. Needs ``flow``
(Debian ``libopm-simulators-bin``); about 10 s.

    python scripts/opm_numerical_dispersivity.py [--records docs/independent_world_v3.json]
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import independent_world as world  # noqa: E402  (the study's schedules, truth and grid)

from spflow.export.opm_deck import write_opm_deck  # noqa: E402
from spflow.export.opm_run import run_opm  # noqa: E402
from spflow.plugins.forward.parameters import default_params  # noqa: E402

FT = 0.3048  # m per ft


def infostep_steps(path: Path) -> tuple[np.ndarray, np.ndarray]:
    """(start time, step length) in days of every step OPM's solver took, from its ``.INFOSTEP`` table."""
    rows = [line.split() for line in path.read_text().splitlines()[1:] if line.strip()]
    table = np.array([[float(r[0]), float(r[1])] for r in rows])
    return table[:, 0], table[:, 1]


def front_crossing(series, slug_start_pv: float, injected_ppm: float) -> float:
    """PV from the start of the polymer slug until the effluent reaches half the injected concentration (linear
    interpolation between report steps)."""
    pv, c = series["pv"].values, series["c_polymer_out"].values / injected_ppm
    i = int(np.argmax(c >= 0.5))
    if c[i] < 0.5:
        raise RuntimeError("the polymer front did not reach the outlet")
    pv_half = pv[i - 1] + (0.5 - c[i - 1]) / (c[i] - c[i - 1]) * (pv[i] - pv[i - 1])
    return float(pv_half - slug_start_pv)


def effluent_dispersivity(series, slug_start_pv: float, slug_pv: float, injected_ppm: float, crossing_pv: float) -> float:
    """The dispersivity, in core lengths, that the effluent polymer's rising edge carries: least-squares fit of the
    step-input solution of the convection-dispersion equation at the outlet (Ogata & Banks 1961, leading term),
    ``c/c0 = erfc((1 - t) / (2 sqrt(a t))) / 2`` with ``t`` the PV since the slug started over ``crossing_pv``,
    over the report steps before the slug's rear reaches the outlet (its half-concentration point is due at
    ``slug_pv / crossing_pv + 1``; the fit stops a quarter of a crossing earlier)."""
    from scipy.optimize import least_squares
    from scipy.special import erfc

    pv, c = series["pv"].values, series["c_polymer_out"].values / injected_ppm
    t = (pv - slug_start_pv) / crossing_pv
    use = (t > 0.0) & (t < slug_pv / crossing_pv + 0.75)

    def residual(x):
        return erfc((1.0 - t[use] / x[1]) / (2.0 * np.sqrt(x[0] * t[use] / x[1]))) / 2.0 - c[use]

    return float(least_squares(residual, [1e-2, 1.0], bounds=([1e-6, 0.5], [1.0, 2.0])).x[0])


def measure(name: str, workdir: Path) -> dict:
    schedule = world.SCHEDULES[name]
    cells = world.SOURCES["opm"]
    deck = write_opm_deck(workdir / name / "CORE.DATA", schedule, world.TRUTH_PARAMS, world.truth_effects("null"),
                          cells=cells, pv_step=world.PV_STEP, max_step_pv=None, log=lambda message: None)
    series = run_opm(deck, workdir=workdir / name, form="series")
    k = next(i for i, s in enumerate(schedule.slugs) if s.polymer_ppm > 0.0)
    start_pv = sum(s.pv for s in schedule.slugs[:k])
    crossing_pv = front_crossing(series, start_pv, schedule.slugs[k].polymer_ppm)
    days_per_pv = float(deck.slug_pv_time_days[k])
    t0, dt = infostep_steps(workdir / name / "CORE.INFOSTEP")
    during = (t0 >= start_pv * days_per_pv) & (t0 < (start_pv + crossing_pv) * days_per_pv)
    dt_pv = float(np.mean(dt[during])) / days_per_pv
    dx = default_params()["LENGTH"] / cells  # m
    v = 1.0 / crossing_pv  # core lengths per PV
    nu = v * dt_pv * cells  # v dt / dx with dx = 1/cells core lengths
    length_ft = default_params()["LENGTH"] / FT
    return {"schedule": name, "cells": cells, "dx_ft": dx / FT, "dt_pv": dt_pv, "steps": int(during.sum()),
            "front_crossing_pv": crossing_pv, "courant": nu, "alpha_num_ft": dx / 2.0 * (1.0 + nu) / FT,
            "alpha_effluent_ft": length_ft * effluent_dispersivity(series, start_pv, schedule.slugs[k].pv,
                                                                   schedule.slugs[k].polymer_ppm, crossing_pv)}


def fitted(records_path: Path) -> list[dict]:
    """The dispersion the diagnosis named on OPM's null data with the dispersion-free base."""
    alpha = default_params()["ALPHAL1"]  # ft: the base's dispersivity the effect strength scales
    records = json.loads(records_path.read_text())["records"]
    return [{"seed": r["seed"], "verdict": r["verdict"], "strength": r["strengths"].get("dispersion"),
             "alpha_ft": r["strengths"]["dispersion"] * alpha if "dispersion" in r["strengths"] else None}
            for r in records if r["source"] == "opm" and r["case"] == "null" and r["variant"] == "dispersion_off"]


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--records", type=Path, default=world.ROOT / "docs" / "independent_world_v3.json")
    args = ap.parse_args(argv)
    with tempfile.TemporaryDirectory(prefix="spflow-opm-dispersivity-") as tmp:
        rows = [measure(name, Path(tmp)) for name in (*world.CALIBRATION, *world.HELDOUT)]
    print("| schedule | cells, dx (ft) | OPM step while the front crosses (PV, steps) | front crossing (PV) | "
          "Courant number nu | alpha_num = dx/2 (1 + nu) (ft) | effluent fit (ft) |")
    print("|---|---|---|---|---|---|---|")
    for r in rows:
        print(f"| {r['schedule']} | {r['cells']}, {r['dx_ft']:.4f} | {r['dt_pv']:.4f} ({r['steps']}) | "
              f"{r['front_crossing_pv']:.3f} | {r['courant']:.2f} | {r['alpha_num_ft']:.4f} | "
              f"{r['alpha_effluent_ft']:.4f} |")
    found = fitted(args.records)
    print()
    print("| seed | verdict | dispersion strength | dispersivity named (ft) | / alpha_num of the calibration schedules |")
    print("|---|---|---|---|---|")
    cal = [r["alpha_num_ft"] for r in rows if r["schedule"] in world.CALIBRATION]
    for f in found:
        ratio = (f"{f['alpha_ft'] / min(cal):.2f}-{f['alpha_ft'] / max(cal):.2f}" if f["alpha_ft"] else "-")
        alpha = f"{f['alpha_ft']:.4f}" if f["alpha_ft"] else "-"
        strength = f"{f['strength']:.3f}" if f["strength"] is not None else "-"
        print(f"| {f['seed']} | {f['verdict']} | {strength} | {alpha} | {ratio} |")


if __name__ == "__main__":
    main()
