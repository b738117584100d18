"""The first step's refits (docs/gap.md, Which). With ``first_step_refits = "shortlist"`` the shortlist is extended
in screen order while the calibration gap is significant and no refit passes: a permeability-reduction twin of the
twin study (``single:permeability_reduction#5``, seed as in ``scripts/gap_validation.py``) whose effect the linear
screen ranks below the shortlist is found. With the default ``"all"``, a twin whose shortlist passes a wrong effect
(``single:permeability_reduction#20``: the shortlist rule declared polymer salinity) is attributed to its truth.
The reference is each twin's own truth, which generated its data."""

import importlib.util
import json
from pathlib import Path

import pytest

from spflow.core.errors import ParameterError
from spflow.plugins.gap.candidates import shortlist
from spflow.plugins.gap.diagnosis import Options, diagnose
from spflow.plugins.gap.report import report_dataset

SCRIPT = Path(__file__).resolve().parents[2] / "scripts" / "gap_validation.py"
spec = importlib.util.spec_from_file_location("gap_validation", SCRIPT)
gv = importlib.util.module_from_spec(spec)
spec.loader.exec_module(gv)


def test_an_effect_the_linear_screen_passes_over_is_refitted_and_found():
    twin = {"scenario": "single:permeability_reduction", "id": "single:permeability_reduction#5",
            "effects": ["permeability_reduction"]}
    base, truth, data = gv.twin(twin, 30, 20334101)
    assert list(truth["effects"]) == ["permeability_reduction"]
    options = Options(first_step_refits="shortlist")
    g = diagnose([data[0]], [data[1]], base, gv.CATALOGUE, options)
    first = g.steps[0]
    screened = [first.screen.names[i] for i in shortlist(first.screen, options.shortlist, options.cos_threshold)]
    assert "permeability_reduction" not in screened           # the linear screen alone would not refit it
    assert "permeability_reduction" in first.shortlisted     # the extension did
    assert g.verdict == "effect" and g.accepted[0][0] == "permeability_reduction"


def test_refitting_every_candidate_first_finds_an_effect_the_shortlist_never_fits():
    twin = {"scenario": "single:permeability_reduction", "id": "single:permeability_reduction#20",
            "effects": ["permeability_reduction"]}
    (spec, index), = gv.select(gv.scenarios(60, 30, 30, 30), [twin["id"]])
    base, truth, data = gv.twin(spec, 30, 20260101 + 1000 * index)
    assert list(truth["effects"]) == ["permeability_reduction"]
    options = Options()
    assert options.first_step_refits == "all"
    g = diagnose([data[0]], [data[1]], base, gv.CATALOGUE, options)
    first = g.steps[0]
    screened = [first.screen.names[i] for i in shortlist(first.screen, options.shortlist, options.cos_threshold)]
    assert "permeability_reduction" not in screened           # the screen's shortlist would not refit it
    assert set(first.shortlisted) == set(gv.CATALOGUE)         # every candidate was refitted
    assert g.verdict == "effect" and g.accepted[0] == ["permeability_reduction"]
    assert json.loads(report_dataset(g).attrs["options"])["first_step_refits"] == "all"  # recorded in the output


def test_an_unknown_first_step_rule_is_refused_before_any_work():
    with pytest.raises(ParameterError, match="first_step_refits = 'some'.*allowed"):
        diagnose(["no_such_file.nc"], [], None, options=Options(first_step_refits="some"))
