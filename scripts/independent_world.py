"""Independent-world study of the gap diagnosis (issue 20): corefloods that spflow's default numerics did not make.

The data come from two simulators other than the diagnosis's base model (spflow, second-order TVD, 60 cells):

* ``opm`` — OPM Flow 2022.10 (fully implicit, first-order upwind, its own tabulated properties) on the deck that
  :func:`spflow.export.opm_deck.write_opm_deck` writes, 100 cells, time steps capped at ``OPM_MAX_STEP_PV`` (its
  converged answer: see there; recorded in every record; skipped with a message when ``flow`` is absent);
* ``upwind_fine`` — spflow itself at very different numerics: first-order upwind on 400 cells.

The world is a Berea-like core (spflow's default core, fluids and Corey curves at the truth's relative-permeability
parameters) flooded with polymer at one salinity (OPM has no surfactant or salinity model): two calibration
schedules (``PF1``, ``PF2``: different slug sizes and concentrations) and one held-out schedule (``PF3``), each
passed through spflow's measurement chain (``spflow.synthetic.measure``, default ``NoiseModel``) with a seed.
Mechanisms outside OPM's polymer model are off in the truth and in the base (shear thinning, dispersion,
capillary desaturation and pressure, kinetic adsorption).

Cases: ``null`` (the base model holds every mechanism of the truth), withheld ``adsorption``, ``ipv``,
``rrf`` (permeability reduction; OPM's acts through adsorbed polymer, so adsorption is on in truth and base) and
``all_three`` (adsorption, IPV and permeability reduction withheld at once). The base calibrates five parameters
over honest ranges (``BASE_PARAMETERS``, the truth inside); the catalogue holds ``CATALOGUE``. Two base variants:
``dispersion_off`` (no dispersion in the base, dispersion a catalogue candidate: the truth has none, but the other
simulator's numerical smearing looks like it) and ``dispersion_calibrated`` (the base calibrates one longitudinal
dispersivity for every phase over 1e-4..0.05 ft, log scale, as a careful engineer does for any real core, whose
dispersion is never zero; dispersion is then not a candidate).

Results accumulate in ``out/independent_world/records.jsonl`` (a re-run skips finished runs, so the study can be
stopped and resumed); the report (``--out``, by default ``report.md`` in the results directory, + ``.json``) is
rebuilt from every record, a partial study included. The committed studies are ``docs/independent_world*.md``.

    python scripts/independent_world.py --seeds 3 --jobs 2            # the whole study (resumable)
    python scripts/independent_world.py --report-only                 # rebuild the report from the records

``--baseline DIR`` adds a comparison with an earlier study's records (``DIR/records.jsonl``) on the runs both have
(same source, base variant, case and seed): the metrics of both side by side and every run whose verdict, named
effects or ambiguity set changed (e.g. a new default of the diagnosis against the records it replaces).
"""

from __future__ import annotations

import argparse
import json
import shutil
import tempfile
import time
from collections import Counter
from pathlib import Path

from spflow.export.opm_deck import write_opm_deck
from spflow.export.opm_run import run_opm
from spflow.export.opm_time_steps import DEFAULT_MAX_STEP_PV
from spflow.io.format import schedule_json
from spflow.plugins.forward.schedule import Schedule, Slug
from spflow.plugins.forward.simulate import simulate
from spflow.plugins.gap.base_model import BaseModel
from spflow.plugins.gap.diagnosis import Options, diagnose
from spflow.plugins.gap.report import report_dataset, summary
from spflow.synthetic import NoiseModel
from spflow.synthetic.measurement import measure

ROOT = Path(__file__).resolve().parents[1]
BRINE = 9400.0
SCHEDULES = {
    "PF1": Schedule((Slug("WF", 0.5, BRINE), Slug("P", 1.0, BRINE, 0.0, 1500.0), Slug("CW", 1.0, BRINE)), "PF1"),
    "PF2": Schedule((Slug("WF", 1.0, BRINE), Slug("P", 0.6, BRINE, 0.0, 800.0), Slug("CW", 1.2, BRINE)), "PF2"),
    "PF3": Schedule((Slug("WF", 0.8, BRINE), Slug("P", 0.5, BRINE, 0.0, 2500.0), Slug("CW", 1.2, BRINE)), "PF3"),
}
CALIBRATION, HELDOUT = ("PF1", "PF2"), ("PF3",)
#: mechanisms outside OPM's polymer model: off in the truth and in the base
OFF = {"shear_thinning": 0.0, "dispersion": 0.0, "capillary_desaturation": 0.0, "capillary_pressure": 0.0,
       "kinetic_adsorption": 0.0}
TRUTH_PARAMS = {"AP1": 18.0, "P1RWC": 0.12, "P2RWC": 0.72, "E1WC": 2.3, "E2WC": 2.3, "E3WC": 2.3, "S2RWC": 0.32}
BASE_PARAMETERS = {
    "AP1": [8.0, 30.0],
    "P1RWC": [0.05, 0.3],
    "P2RWC": [0.5, 1.0],
    "n_low": {"names": ["E1WC", "E2WC", "E3WC"], "range": [1.5, 3.0]},
    "S2RWC": [0.2, 0.4],
}
ADS, IPV, RRF = "polymer_adsorption", "inaccessible_pore_volume", "permeability_reduction"
#: case -> (truth effects on, withheld from the base)
CASES = {
    "null": ((), ()),
    "adsorption": ((ADS,), (ADS,)),
    "ipv": ((IPV,), (IPV,)),
    "rrf": ((ADS, RRF), (RRF,)),
    "all_three": ((ADS, IPV, RRF), (ADS, IPV, RRF)),
}
CATALOGUE = [ADS, IPV, RRF, "dispersion", "capillary_pressure", "shear_thinning", "reversible_polymer_adsorption"]
DISPERSIVITY = {"names": ["ALPHAL1", "ALPHAL2", "ALPHAL3"], "range": [1.0e-4, 0.05], "scale": "log"}
VARIANTS = ("dispersion_off", "dispersion_calibrated")
#: effects the search may add (the first variant ran with the diagnosis's default 2, the second allows the three
#: withheld ones of ``all_three``)
MAX_EFFECTS = {"dispersion_off": 2, "dispersion_calibrated": 3}
SOURCES = {"opm": 100, "upwind_fine": 400}
BASE_CELLS = 60
PV_STEP = 0.01
# OPM Flow's time steps are capped at this many PV (the library's default): with OPM's own step control (up to a
# report step, 0.01 PV) the fully implicit scheme's time error dominated the data (the pre-breakthrough dp of the
# null flood PF3 at 0.3 PV 8 % high; spflow.export.opm_time_steps.DEFAULT_MAX_STEP_PV, docs/independent_world_v6.md); a
# real core has no time-step error, so the data take the converged steps. independent_world_v6 passed the cap as
# flow's global --solver-max-time-step-in-days at the same value: the schedules here inject at one rate, so the
# deck's per-slug TUNING cap takes the same steps
OPM_MAX_STEP_PV = DEFAULT_MAX_STEP_PV
VARIABLES = ("dp", "oil_cut", "c_polymer_out")


def truth_effects(case: str) -> dict[str, float]:
    """Effect strengths of the truth: every polymer mechanism off except the case's."""
    on, _ = CASES[case]
    return OFF | {e: (1.0 if e in on else 0.0) for e in (ADS, IPV, RRF)}


def base_model(case: str, variant: str = "dispersion_off") -> BaseModel:
    """The diagnosis's base: the truth's mechanisms minus the withheld ones, five calibrated parameters (six with
    the calibrated dispersivity of the ``dispersion_calibrated`` variant)."""
    on, withheld = CASES[case]
    effects = OFF | {e: (1.0 if e in on and e not in withheld else 0.0) for e in (ADS, IPV, RRF)}
    parameters = dict(BASE_PARAMETERS)
    if variant == "dispersion_calibrated":
        effects["dispersion"] = 1.0
        parameters["alpha_L"] = DISPERSIVITY
    return BaseModel.from_mapping({"cells": BASE_CELLS, "effects": effects, "parameters": parameters})


def catalogue(variant: str) -> list[str]:
    return [c for c in CATALOGUE if variant != "dispersion_calibrated" or c != "dispersion"]


def clean_run(source: str, case: str, name: str, workdir: Path):
    """The noise-free series of one schedule from ``source`` (a ``simulate()``-like Dataset)."""
    effects = truth_effects(case)
    sched = SCHEDULES[name]
    if source == "upwind_fine":
        return simulate(sched, TRUTH_PARAMS, cells=SOURCES[source], effects=effects, scheme="upwind",
                        pv_step=PV_STEP)
    deck = write_opm_deck(workdir / f"{case}_{name}" / "CORE.DATA", sched, TRUTH_PARAMS, effects,
                          cells=SOURCES[source], pv_step=PV_STEP, max_step_pv=OPM_MAX_STEP_PV,
                          log=lambda message: None)
    return run_opm(deck, form="series")


def corefloods(source: str, case: str, seed: int, workdir: Path) -> dict[str, object]:
    """The lab-like corefloods of one run: every schedule through the measurement chain with its own seed."""
    out = {}
    for k, name in enumerate((*CALIBRATION, *HELDOUT)):
        clean = clean_run(source, case, name, workdir)
        out[name] = measure(clean, NoiseModel(), 1000 * seed + k, experiment=name,
                            source=f"independent-world study: {source}", schedule=schedule_json(SCHEDULES[name]))
    return out


def run_one(source: str, case: str, seed: int, jobs: int, variant: str = "dispersion_off",
            max_effects: int | None = None) -> dict:
    """Generate one run's data, diagnose it and return its record (``max_effects``: the search's cap, default
    the variant's ``MAX_EFFECTS``)."""
    max_effects = MAX_EFFECTS[variant] if max_effects is None else max_effects
    from joblib import Parallel

    start = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="spflow-iw-") as tmp:
        data = corefloods(source, case, seed, Path(tmp))
    with Parallel(n_jobs=jobs) as parallel:
        diag = diagnose([data[n] for n in CALIBRATION], [data[n] for n in HELDOUT], base_model(case, variant),
                        catalogue(variant),
                        Options(variables=VARIABLES, pv_step=0.1, max_effects=max_effects),
                        parallel=parallel if jobs > 1 else None)
    result = summary(report_dataset(diag))
    return {"source": source, "variant": variant, "max_effects": max_effects, "case": case, "seed": seed,
            "truth": list(CASES[case][1]), "opm_max_step_pv": OPM_MAX_STEP_PV if source == "opm" else None,
            "verdict": result["verdict"], "effects": [e["name"] for e in result["effects"]],
            "strengths": {e["name"]: e["strength"] for e in result["effects"]},
            "ambiguity_set": result["ambiguity_set"], "chi2_base": result["fit"]["chi2_base"],
            "dof": result["fit"]["dof"], "gap_closed": result["gap_closed"],
            "numerical_scale": ((result["numerical_error"] or {}).get("scale") or {}).get("estimate"),
            "forward_runs": result["forward_runs"], "diagnosis_s": diag.wall_time_s,
            "heldout_predictive": diag.options.heldout_predictive, "heldout_weights": result["heldout_weights"],
            "heldout_unreliable": result["heldout_unreliable"], "wall_s": time.perf_counter() - start}


def classify(record: dict) -> str:
    """Confusion-matrix column of a record: what the diagnosis named against the withheld truth."""
    named, truth = set(record["effects"]), set(record["truth"])
    if not named:
        return "nothing named" if truth else "none (correct)"
    if named == truth:
        return "exactly the truth"
    if truth and truth <= named:
        return "truth + spurious"
    if named & truth:
        return "part of the truth"
    return "wrong mechanism"


def metrics(records: list[dict]) -> dict:
    null = [r for r in records if not r["truth"]]
    single = [r for r in records if len(r["truth"]) == 1]
    triple = [r for r in records if len(r["truth"]) == 3]
    sets = [set(r["ambiguity_set"] or r["effects"]) for r in single]
    return {
        "runs": len(records),
        "null_false_alarms": sum(bool(r["effects"]) for r in null), "null_runs": len(null),
        "truth_first": sum(bool(r["effects"]) and r["effects"][0] == r["truth"][0] for r in single),
        "truth_in_set": sum(r["truth"][0] in s for r, s in zip(single, sets)), "single_runs": len(single),
        "mean_set_size": (sum(len(s) for s in sets) / len(sets)) if sets else None,
        "all_three_named": sum(set(r["truth"]) <= set(r["effects"]) for r in triple), "triple_runs": len(triple),
    }


def _key(record: dict) -> tuple:
    """What identifies a run: source, base variant, case and seed (records of the first study carry no variant)."""
    return record["source"], record.get("variant", VARIANTS[0]), record["case"], record["seed"]


def _outcome(record: dict) -> str:
    """What a run concluded: verdict, named effects and ambiguity set (set order does not count)."""
    return (f"{record['verdict']}, {', '.join(record['effects']) or '-'}, "
            f"{{{', '.join(sorted(record['ambiguity_set']))}}}")


def baseline_section(records: list[dict], baseline: list[dict], label: str) -> tuple[list[str], dict]:
    """Markdown lines and JSON payload comparing ``records`` with an earlier study's ``baseline`` on the runs both
    have (:func:`_key`): the metrics of both per source and base variant, and the runs whose outcome changed."""
    theirs = {_key(r): r for r in baseline}
    common = [r for r in records if _key(r) in theirs]
    lines = [f"## Against the baseline `{label}` ({len(common)} runs both have)", ""]
    payload = {"baseline": label, "runs": len(common), "metrics": {}, "changed": []}
    if not common:
        return lines + ["No run in common.", ""], payload
    lines += ["| source / base | runs | null false alarms | truth first | truth in set | mean set size | "
              "all three named |", "|---|---|---|---|---|---|---|"]
    for source, variant in ((s, v) for s in SOURCES for v in VARIANTS):
        ours = [r for r in common if r["source"] == source and r.get("variant", VARIANTS[0]) == variant]
        if not ours:
            continue
        a, b = metrics(ours), metrics([theirs[_key(r)] for r in ours])
        payload["metrics"][f"{source}/{variant}"] = {"study": a, "baseline": b}

        def pair(key, total=None):
            both = [b[key], a[key]]
            text = " -> ".join("-" if x is None else f"{x:.2f}" if isinstance(x, float) else str(x) for x in both)
            return text + (f" of {a[total]}" if total else "")

        lines.append(f"| {source} / {variant} | {len(ours)} | {pair('null_false_alarms', 'null_runs')} | "
                     f"{pair('truth_first', 'single_runs')} | {pair('truth_in_set', 'single_runs')} | "
                     f"{pair('mean_set_size')} | {pair('all_three_named', 'triple_runs')} |")
    changed = [(theirs[_key(r)], r) for r in common if _outcome(theirs[_key(r)]) != _outcome(r)]
    lines += ["", f"Runs whose verdict, named effects or ambiguity set changed: {len(changed)} of {len(common)}", ""]
    if changed:
        lines += ["| source / base | case | seed | baseline: verdict, named, set | study: verdict, named, set |",
                  "|---|---|---|---|---|"]
    for old, new in changed:
        lines.append(f"| {new['source']} / {new.get('variant', VARIANTS[0])} | {new['case']} | {new['seed']} | "
                     f"{_outcome(old)} | {_outcome(new)} |")
        payload["changed"].append({"key": list(_key(new)), "baseline": _outcome(old), "study": _outcome(new)})
    return lines + [""], payload


def write_report(records: list[dict], out: Path, store: Path, baseline: tuple[str, list[dict]] | None = None,
                 ) -> None:
    """The report ``out`` (markdown) and its ``.json`` twin from all records of ``store`` (a partial study says
    so), with a comparison against ``baseline`` (label, records) when given."""
    columns = ["none (correct)", "nothing named", "exactly the truth", "truth + spurious", "part of the truth",
               "wrong mechanism"]
    lines = ["# Independent-world study of the gap diagnosis", "",
             f"Generated by `scripts/independent_world.py` from `{_shown(store)}`; the protocol "
             "is in the script's docstring and in `docs/gap.md`.", ""]
    for source, variant in ((s, v) for s in SOURCES for v in VARIANTS):
        rows = [r for r in records if r["source"] == source and r.get("variant", VARIANTS[0]) == variant]
        if not rows:
            lines += [f"## {source}, base {variant}", "", "No runs yet.", ""]
            continue
        m = metrics(rows)
        lines += [f"## {source}, base {variant} ({m['runs']} runs of {len(CASES) * max(r['seed'] for r in rows)} "
                  "planned)", "",
                  "| truth case | " + " | ".join(columns) + " |", "|---|" + "---|" * len(columns)]
        for case in CASES:
            count = Counter(classify(r) for r in rows if r["case"] == case)
            lines.append(f"| {case} | " + " | ".join(str(count.get(c, 0)) for c in columns) + " |")
        lines += ["", f"- null runs naming a physical mechanism: {m['null_false_alarms']} of {m['null_runs']} "
                      "(target <= 1 in 10)",
                  f"- single withheld effect named first: {m['truth_first']} of {m['single_runs']} (target >= 80 %)",
                  f"- truth inside the ambiguity set: {m['truth_in_set']} of {m['single_runs']}, mean set size "
                  f"{m['mean_set_size'] if m['mean_set_size'] is None else round(m['mean_set_size'], 2)} "
                  "(targets >= 90 %, <= 2)",
                  f"- all three named when three are withheld: {m['all_three_named']} of {m['triple_runs']} "
                  "(target >= 2 of 3 seeds)", "",
                  "| case | seed | verdict | named (strength) | ambiguity set | base chi2 / dof | "
                  "sampled scores with Pareto k > 0.7 | forward runs | diagnosis s |",
                  "|---|---|---|---|---|---|---|---|---|"]
        for r in sorted(rows, key=lambda r: (list(CASES).index(r["case"]), r["seed"])):
            named = ", ".join(f"{k} ({v:.3g})" for k, v in r["strengths"].items()) or "-"
            # (records from before the weights were recorded, or with linearised scores: "-")
            unreliable = (f"{len(r['heldout_unreliable'])} of {len(r['heldout_weights'])}"
                          if r.get("heldout_weights") else "-")
            lines.append(f"| {r['case']} | {r['seed']} | {r['verdict']} | {named} | "
                         f"{', '.join(r['ambiguity_set']) or '-'} | {r['chi2_base']:.0f} / {r['dof']:.0f} | "
                         f"{unreliable} | {r['forward_runs']} | {r['diagnosis_s']:.0f} |")
        lines.append("")
    extra = {}
    if baseline is not None:
        section, extra["against_baseline"] = baseline_section(records, baseline[1], baseline[0])
        lines += section
    out.write_text("\n".join(lines))
    out.with_suffix(".json").write_text(json.dumps(
        {"records": records, "metrics": {f"{s}/{v}": metrics([r for r in records if r["source"] == s
                                                              and r.get("variant", VARIANTS[0]) == v])
                                         for s in SOURCES for v in VARIANTS}} | extra,
        indent=1))


def _shown(path: Path) -> str:
    """``path`` relative to the repository when inside it (as the report cites it)."""
    path = path.resolve()
    return str(path.relative_to(ROOT)) if path.is_relative_to(ROOT) else str(path)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=3, help="noise seeds per case and source (1..N)")
    parser.add_argument("--sources", nargs="+", default=list(SOURCES), choices=list(SOURCES))
    parser.add_argument("--cases", nargs="+", default=list(CASES), choices=list(CASES))
    parser.add_argument("--variants", nargs="+", default=list(VARIANTS), choices=list(VARIANTS))
    parser.add_argument("--max-effects", type=int, default=None,
                        help="the search's cap on added effects for every variant (default: the variant's, "
                             f"{MAX_EFFECTS}); use another --results directory, records are keyed without it")
    parser.add_argument("--jobs", type=int, default=1)
    parser.add_argument("--results", default=str(ROOT / "out" / "independent_world"))
    parser.add_argument("--report-only", action="store_true")
    parser.add_argument("--baseline", metavar="DIR",
                        help="an earlier study's results directory: compare with its records on the runs both have")
    parser.add_argument("--out", help="the report (markdown; its .json next to it; default: report.md in --results)")
    args = parser.parse_args(argv)
    results = Path(args.results)
    results.mkdir(parents=True, exist_ok=True)
    store = results / "records.jsonl"
    out = Path(args.out) if args.out else results / "report.md"
    records = [json.loads(line) for line in store.read_text().splitlines()] if store.is_file() else []
    baseline = None
    if args.baseline is not None:
        file = Path(args.baseline) / "records.jsonl"
        if not file.is_file():
            raise SystemExit(f"--baseline {args.baseline}: no records.jsonl there")
        baseline = (_shown(Path(args.baseline)), [json.loads(line) for line in file.read_text().splitlines()])
    if not args.report_only:
        done = {_key(r) for r in records}
        sources = [s for s in args.sources if s != "opm" or shutil.which("flow")]
        if len(sources) < len(args.sources):
            print("OPM Flow ('flow') is not on PATH: the opm source is skipped (apt-get install libopm-simulators-bin)")
        plan = [(s, v, c, k) for s in sources for v in args.variants for k in range(1, args.seeds + 1)
                for c in args.cases if (s, v, c, k) not in done]
        print(f"{len(plan)} run(s) to do, {len(done)} done")
        for source, variant, case, seed in plan:
            record = run_one(source, case, seed, args.jobs, variant, args.max_effects)
            records.append(record)
            with store.open("a") as fh:
                fh.write(json.dumps(record) + "\n")
            print(f"{source} {variant} {case} seed {seed}: {record['verdict']} {record['effects']} "
                  f"set {record['ambiguity_set']} ({record['wall_s']:.0f} s)", flush=True)
            write_report(records, out, store, baseline)
    write_report(records, out, store, baseline)
    print(f"report: {out} ({len(records)} runs)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
