"""Reruns of a diagnosis along other optimiser paths (``path_stability.py``): the difference-step factors written out
by hand, the agreement rule on stand-in reruns (set order and strengths do not matter, names and verdicts do), and
an out-of-range count refused before any work. The end-to-end check that a rerun is the diagnosis with that
difference step is in test_diagnose_independent.py."""

import pytest

from spflow.core.errors import ParameterError
from spflow.plugins.gap.diagnosis import Options, diagnose
from spflow.plugins.gap.path_stability import rerun_paths, step_factors
from spflow.plugins.gap.stage import Diagnose


def test_the_difference_step_alternates_around_the_main_runs_in_tenths():
    assert step_factors(0) == []
    assert step_factors(5) == pytest.approx([1.1, 0.9, 1.2, 0.8, 1.3])
    with pytest.raises(ValueError, match="0..5"):
        step_factors(6)


def test_a_rerun_agrees_on_the_same_verdict_set_and_effect_names_only():
    outcomes = {1.1: ("ambiguous", ["b", "a"], {"a": 0.7}, 10),   # same set in another order, other strength
                0.9: ("effect", ["a"], {"a": 0.9}, 11),            # another verdict and set
                1.2: ("ambiguous", ["a", "b"], {"b": 0.9}, 12)}    # another declared effect
    steps = []

    def rerun(step):
        steps.append(step)
        return outcomes[round(step / 0.02, 6)]

    out = rerun_paths(rerun, 0.02, 3, "ambiguous", ["a", "b"], {"a": 0.8})
    assert steps == pytest.approx([0.022, 0.018, 0.024])
    assert [r.agrees for r in out] == [True, False, False]
    assert out[0].as_dict() == {"diff_step": steps[0], "verdict": "ambiguous", "ambiguity_set": ["b", "a"],
                                "effects": {"a": 0.7}, "forward_runs": 10, "agrees": True}


def test_an_out_of_range_count_is_refused_before_any_work():
    with pytest.raises(ParameterError, match="path_reruns = 6 is out of range; allowed 0..5"):
        diagnose(["no_such_file.nc"], [], None, options=Options(path_reruns=6))
    with pytest.raises(ParameterError, match="path_reruns"):
        Diagnose(path_reruns=6)
