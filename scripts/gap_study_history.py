"""The headline metrics of the committed withheld-effect twin studies side by side (docs/gap_validation.md).

Reads the JSON reports that ``scripts/gap_validation.py`` writes next to its Markdown (``docs/gap_validation_v*.json``)
and prints one Markdown table: a row per report and likelihood set, and a row per next-experiment phase of that set
(the study-wide metrics with each done twin's result replaced by its result after the added coreflood, as the
report's own "after the proposed next experiment" section computes them). Nothing is recomputed from the twins: the
table repeats what each report says, so a row is exactly as comparable as its report (the studies differ in their
twins when one was stopped part-way, and older reports lack the SNR definitions that came later: shown as "–").

    python scripts/gap_study_history.py docs/gap_validation_v1.json docs/gap_validation_v6.json ...
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

#: the SNR definitions of the targets, in the order the cells list them (report metric suffixes)
VIEWS = ("snr3", "absorbed_snr3", "beyond_numerics_snr3")
#: (column heading, report metric stem) of the three-view columns
RATES = (("detection", "detection"), ("correct first", "top1"), ("truth in the set", "truth_in_set"))


def _value(metrics: dict, name: str) -> float | None:
    entry = metrics.get(name)
    return None if entry is None else entry["value"]


def _cell(values: list[float | None], spec: str = ".3f") -> str:
    return " / ".join("–" if v is None else format(v, spec) for v in values)


def _row(label: str, section: str, twins: str, metrics: dict, cpu: str) -> str:
    """A table row from ``metrics`` (report metric name -> value; absent: "–")."""
    null = metrics.get("false_alarm_null")
    alarms = "–" if null is None else f"{round(null['value'] * null['n'])}/{null['n']}"
    rates = [_cell([_value(metrics, f"{stem}_{view}") for view in VIEWS]) for _, stem in RATES]
    size = _cell([_value(metrics, "mean_set_size_beyond_numerics_snr3")], ".2f")
    return f"| {label} | {section} | {twins} | {alarms} | " + " | ".join(rates) + f" | {size} | {cpu} |"


def history(files: list[Path]) -> list[str]:
    """The Markdown table of the reports ``files`` (module docstring), in the order given."""
    head = ["report", "likelihood", "twins", "false alarms (null)"]
    head += [f"{name} (SNR ≥ 3: projected / absorbed / beyond numerics)" for name, _ in RATES]
    head += ["mean set size (beyond numerics)", "median CPU s per twin"]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for path in files:
        report = json.loads(Path(path).read_text())
        sets = report.get("sets") if isinstance(report, dict) else None
        if not isinstance(sets, dict) or not all(isinstance(p, dict) and {"metrics", "twins"} <= p.keys()
                                                 for p in sets.values()):
            raise SystemExit(f"{path}: not a report of scripts/gap_validation.py (it needs 'sets', each with "
                             "'metrics' and 'twins')")
        for section, payload in sets.items():
            metrics = payload["metrics"]
            cpu = metrics.get("cpu_s_per_twin")
            lines.append(_row(Path(path).stem, section, str(len(payload["twins"])), metrics,
                              "–" if cpu is None else f"{cpu['value']:.0f}"))
            for key, phase in payload.items():
                if not key.startswith("next_experiment_"):
                    continue
                done = phase["metrics"]
                size = done["phase"] if "phase" in done else done["ambiguous"]  # (before stage 8 reports the phase held ambiguous twins)
                after = {name: entry["after"] for name, entry in done["study"].items()}
                lines.append(_row(f"{Path(path).stem} + next experiment ({phase['added_as']})", section,
                                  f"{done['done']} of {size} re-diagnosed", after, "–"))
    return lines


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("reports", nargs="+", type=Path, help="JSON reports of scripts/gap_validation.py")
    args = p.parse_args(argv)
    print("\n".join(history(args.reports)))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
