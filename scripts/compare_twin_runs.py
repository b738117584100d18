"""Paired comparison of two runs of the twin study on the same twins (e.g. a decision-rule change rerun on the
twins it can affect): the metrics of ``scripts/gap_validation.py`` on the twins both result files hold, before and
after, and every twin whose verdict, accepted effects or ambiguity set changed.

    python scripts/compare_twin_runs.py BEFORE.jsonl AFTER.jsonl --title "..." --out docs/FILE.md

Twins are matched by id (scenario and seed; the same twin data when both runs used the study's seeds). The
metrics are those of the full study restricted to the matched twins, so on a selected subset they measure the
change, not the study-wide rates; twins only in AFTER (e.g. null twins the first run had not reached) are counted
on their own.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from gap_validation import metrics  # noqa: E402  (the study's own metric definitions)


def _load(path: Path) -> dict[str, dict]:
    return {r["id"]: r for r in map(json.loads, path.read_text().splitlines())}


def _outcome(r: dict) -> str:
    steps = " then ".join("/".join(s) for s in r["accepted"]) or "-"
    strengths = ", ".join(f"{k} {v:.3g}" for k, v in r["fitted_strengths"].items())
    return f"{r['verdict']} {steps}" + (f" ({strengths})" if strengths else "")


def _truth(r: dict) -> str:
    return ", ".join(f"{k} {v:.3g}" for k, v in r["truth_effects"].items()) or "-"


def compare(before: dict[str, dict], after: dict[str, dict], title: str, commands: list[str]) -> list[str]:
    """Markdown lines of the comparison."""
    ids = [i for i in after if i in before]
    m0, m1 = metrics([before[i] for i in ids]), metrics([after[i] for i in ids])
    lines = [f"# {title}", "", *commands, "",
             f"Twins in both runs: {len(ids)}; only in the second: {len(after) - len(ids)}.", "",
             "| metric (matched twins) | before | after | n |", "|---|---|---|---|"]
    for key, v1 in m1.items():
        v0 = m0.get(key, {"value": None})
        fmt = lambda x: "-" if x is None else f"{x:.3g}"  # noqa: E731
        if key.startswith(("cpu_s", "forward_runs")):
            continue
        lines.append(f"| {key} | {fmt(v0['value'])} | {fmt(v1['value'])} | {v1['n']} |")
    only = [after[i] for i in after if i not in before]
    if only:
        m2 = metrics(only)
        lines += ["", "Twins only in the second run:", "", "| metric | value | n |", "|---|---|---|"]
        lines += [f"| {k} | {v['value']:.3g} | {v['n']} |" for k, v in m2.items()
                  if v["n"] and v["value"] is not None and not k.startswith(("cpu_s", "forward_runs"))]
    changed = [i for i in ids if (before[i]["verdict"], before[i]["accepted"], before[i]["ambiguity_set"])
               != (after[i]["verdict"], after[i]["accepted"], after[i]["ambiguity_set"])]
    lines += ["", f"Changed outcomes ({len(changed)} of {len(ids)}):", "",
              "| twin | truth | SNR | before | after |", "|---|---|---|---|---|"]
    lines += [f"| {i} | {_truth(after[i])} | {after[i]['snr']:.1f} | {_outcome(before[i])} | {_outcome(after[i])} |"
              for i in changed]
    return lines


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("before", type=Path)
    parser.add_argument("after", type=Path)
    parser.add_argument("--title", default="Twin study: paired comparison")
    parser.add_argument("--command", action="append", default=[], help="a line saying how a run was made")
    parser.add_argument("--out", type=Path, help="markdown file (default: print)")
    args = parser.parse_args(argv)
    lines = compare(_load(args.before), _load(args.after), args.title, args.command)
    if args.out:
        args.out.write_text("\n".join(lines) + "\n")
        print(f"wrote {args.out}")
    else:
        print("\n".join(lines))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
