"""The independent-world study's comparison with a baseline study (scripts/independent_world.py --baseline) on
hand-made records: only runs both studies have are compared, metrics counted by hand, changed runs listed."""

import importlib.util
from pathlib import Path

SCRIPT = Path(__file__).resolve().parents[2] / "scripts" / "independent_world.py"
spec = importlib.util.spec_from_file_location("independent_world", SCRIPT)
iw = importlib.util.module_from_spec(spec)
spec.loader.exec_module(iw)


def run(case, seed, verdict, effects, ambiguity, truth):
    return {"source": "opm", "variant": "dispersion_off", "case": case, "seed": seed, "truth": truth,
            "verdict": verdict, "effects": effects, "ambiguity_set": ambiguity}


def test_only_common_runs_are_compared_and_changed_ones_are_listed():
    baseline = [run("null", 1, "effect", ["dispersion"], ["dispersion"], []),
                run("ipv", 1, "effect", ["inaccessible_pore_volume"], ["inaccessible_pore_volume"],
                    ["inaccessible_pore_volume"]),
                run("ipv", 2, "effect", ["inaccessible_pore_volume"], ["inaccessible_pore_volume"],
                    ["inaccessible_pore_volume"])]
    study = [run("null", 1, "none", [], [], []),                                # changed: the false alarm is gone
             run("ipv", 1, "ambiguous", ["inaccessible_pore_volume"],           # changed: a second set member
                 ["inaccessible_pore_volume", "dispersion"], ["inaccessible_pore_volume"]),
             run("adsorption", 1, "effect", ["polymer_adsorption"], ["polymer_adsorption"],  # not in the baseline
                 ["polymer_adsorption"])]
    lines, payload = iw.baseline_section(study, baseline, "old")
    assert payload["runs"] == 2
    m = payload["metrics"]["opm/dispersion_off"]
    assert (m["baseline"]["null_false_alarms"], m["study"]["null_false_alarms"]) == (1, 0)
    assert (m["baseline"]["mean_set_size"], m["study"]["mean_set_size"]) == (1.0, 2.0)
    assert [c["key"] for c in payload["changed"]] == [["opm", "dispersion_off", "null", 1],
                                                      ["opm", "dispersion_off", "ipv", 1]]
    row = "| opm / dispersion_off | 2 | 1 -> 0 of 1 | 1 -> 1 of 1 | 1 -> 1 of 1 | 1.00 -> 2.00 | 0 -> 0 of 0 |"
    assert row in lines
    assert "Runs whose verdict, named effects or ambiguity set changed: 2 of 2" in lines
