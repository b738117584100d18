"""The decision rule on constructed scores: pass/fail conditions, ambiguity sets, and the four verdicts."""

import numpy as np

from spflow.plugins.gap.verdict import CandidateScore, Rule, ambiguity_set, passes, verdict

RULE = Rule()


def score(name, delta, se, physical=True, closed=0.9, gradient=None, strength_z=5.0, chi2_drop=50.0):
    return CandidateScore(name, delta, se, 10 * se, 1.0, strength_z, physical, closed, chi2_drop,
                          np.zeros(5) if gradient is None else np.asarray(gradient, float))


def test_pass_needs_gain_significance_and_a_physical_present_strength():
    assert passes(score("a", 10.0, 3.0), RULE)
    assert not passes(score("a", 3.9, 0.1), RULE)         # below 4 nats
    assert not passes(score("a", 10.0, 5.5), RULE)        # under 2 SE
    assert not passes(score("a", 10.0, 1.0, physical=False), RULE)
    assert not passes(score("a", float("nan"), 1.0), RULE)
    assert not passes(score("a", 10.0, 1.0, strength_z=1.5), RULE)   # strength not distinguishable from the base
    assert passes(score("a", 10.0, 1.0, strength_z=-2.5), RULE)      # weaker than the base, significantly
    assert not passes(score("a", 10.0, 1.0, chi2_drop=3.0), RULE)    # the calibration data do not ask for it


def test_ambiguity_set_uses_the_pairwise_measurement_se():
    best = score("a", 50.0, 5.0, gradient=[0, 0, 0, 0, 0])
    close = score("b", 45.0, 5.0, gradient=[3, 0, 0, 0, 0])    # 5 below the best, pairwise SE 3: within 2 SE
    far = score("c", 20.0, 5.0, gradient=[0, 4, 0, 0, 0])      # 30 below, SE 4: outside
    failing = score("d", 49.0, 30.0)
    assert [s.name for s in ambiguity_set([far, close, best, failing], RULE)] == ["a", "b"]
    assert ambiguity_set([failing], RULE) == []


def test_verdicts():
    assert verdict([["a"]], True, 0.8, [], RULE) == ("effect", ["a"])
    assert verdict([["a", "b"]], True, 0.8, [], RULE) == ("ambiguous", ["a", "b"])
    assert verdict([["a"], ["b", "c"]], True, 0.9, [], RULE) == ("ambiguous", ["a"])
    assert verdict([["a"]], True, 0.3, [], RULE) == ("out_of_catalogue", [])   # helps, closes < half the gap
    assert verdict([["a"]], False, float("nan"), [], RULE) == ("none", [])  # a gain only out of sample
    assert verdict([], True, 0.0, ["a", "b"], RULE) == ("ambiguous", ["a", "b"])  # unconfirmed closers
    assert verdict([], True, 0.0, [], RULE) == ("out_of_catalogue", [])
    assert verdict([], False, 0.0, [], RULE) == ("none", [])
