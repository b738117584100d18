"""The first step's shortlist is extended in screen order while the calibration gap is significant and no refit
passes (docs/gap.md, Which): a permeability-reduction twin of the twin study (``single:permeability_reduction#5``,
seed as in ``scripts/gap_validation.py``) whose effect the linear screen ranks below the shortlist is found. The
reference is the twin's own truth, which generated its data."""

import importlib.util
from pathlib import Path

from spflow.plugins.gap.candidates import shortlist
from spflow.plugins.gap.diagnosis import Options, diagnose

SCRIPT = Path(__file__).resolve().parents[2] / "scripts" / "gap_validation.py"
spec = importlib.util.spec_from_file_location("gap_validation", SCRIPT)
gv = importlib.util.module_from_spec(spec)
spec.loader.exec_module(gv)


def test_an_effect_the_linear_screen_passes_over_is_refitted_and_found():
    twin = {"scenario": "single:permeability_reduction", "id": "single:permeability_reduction#5",
            "effects": ["permeability_reduction"]}
    base, truth, data = gv.twin(twin, 30, 20334101)
    assert list(truth["effects"]) == ["permeability_reduction"]
    options = Options()
    g = diagnose([data[0]], [data[1]], base, gv.CATALOGUE, options)
    first = g.steps[0]
    screened = [first.screen.names[i] for i in shortlist(first.screen, options.shortlist, options.cos_threshold)]
    assert "permeability_reduction" not in screened           # the linear screen alone would not refit it
    assert "permeability_reduction" in first.shortlisted     # the extension did
    assert g.verdict == "effect" and g.accepted[0][0] == "permeability_reduction"
