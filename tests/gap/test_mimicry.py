"""scripts/mimicry.py: the cosine between a twin's true departure and a catalogue effect's change is exactly 1
when the effect is the twin's own truth at its true strength, close to 1 at a nearby strength, and not a number
for an effect step 0 did not fit."""

import importlib.util
from pathlib import Path

import numpy as np
import pytest

SCRIPT = Path(__file__).resolve().parents[2] / "scripts" / "mimicry.py"
spec = importlib.util.spec_from_file_location("mimicry", SCRIPT)
mimicry = importlib.util.module_from_spec(spec)
spec.loader.exec_module(mimicry)
gv = mimicry.gap_validation

CELLS = 10


def _record(scenario, seed, step0):
    return {"id": f"{scenario}#0", "scenario": scenario, "seed": seed, "cells": CELLS,
            "variables": ["dp", "oil_cut"], "step0": step0, "verdict": "effect", "accepted": [],
            "truth_effects": {}, "truth_fixed": {}}


def test_an_effect_mimics_itself_exactly_at_the_true_strength():
    record = _record("single:polymer_adsorption", 20260101, [])
    _, truth, _ = gv.twin(gv.twin_spec(record), CELLS, record["seed"])
    strength = truth["effects"]["polymer_adsorption"]
    record["step0"] = [{"name": "polymer_adsorption", "strength": strength}]
    c = mimicry.cosines(record, "polymer_adsorption")
    assert c["strength"] == strength
    for kind in ("raw", "projected", "exact"):
        assert c[kind] == pytest.approx(1.0, abs=1e-12)


def test_another_strength_of_a_one_sided_change_keeps_the_cosine_near_one_and_an_untried_effect_is_nan():
    record = _record("single:polymer_adsorption", 20260101, [])
    _, truth, _ = gv.twin(gv.twin_spec(record), CELLS, record["seed"])
    record["step0"] = [{"name": "polymer_adsorption", "strength": 0.9 * truth["effects"]["polymer_adsorption"]}]
    near = mimicry.cosines(record, "polymer_adsorption")
    assert 0.9 < near["raw"] <= 1.0 + 1e-12
    assert np.isnan(mimicry.cosines(record, "capillary_pressure")["raw"])
