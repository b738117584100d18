"""The decision rule on constructed scores: pass/fail conditions, competitors, over-dispersion, ambiguity sets,
and the five verdicts."""

import numpy as np

from spflow.plugins.gap.verdict import CandidateScore, Rule, ambiguity_set, passes, targeted_pvalue, verdict

RULE = Rule()


def score(name, delta, se, physical=True, closed=0.9, gradient=None, strength_z=5.0, chi2_drop=50.0,
          competitor=(float("nan"), float("nan")), dispersion=1.0):
    return CandidateScore(name, delta, se, 10 * se, 1.0, strength_z, physical, closed, chi2_drop,
                          np.zeros(5) if gradient is None else np.asarray(gradient, float), *competitor, dispersion)


def test_pass_needs_gain_significance_and_a_physical_present_strength():
    assert passes(score("a", 10.0, 3.0), RULE)
    assert not passes(score("a", 3.9, 0.1), RULE)         # below 4 nats
    assert not passes(score("a", 10.0, 5.5), RULE)        # under 2 SE
    assert not passes(score("a", 10.0, 1.0, physical=False), RULE)
    assert not passes(score("a", float("nan"), 1.0), RULE)
    assert not passes(score("a", 10.0, 1.0, strength_z=1.5), RULE)   # strength not distinguishable from the base
    assert passes(score("a", 10.0, 1.0, strength_z=-2.5), RULE)      # weaker than the base, significantly
    assert not passes(score("a", 10.0, 1.0, chi2_drop=3.0), RULE)    # the calibration data do not ask for it


def test_a_candidate_must_beat_the_discrepancy_competitor_by_the_same_margins():
    # 10 nats over the base, but only 3 over the competitor (under min_delta 4): tried, not declared
    assert not passes(score("a", 10.0, 1.0, competitor=(3.0, 0.5)), RULE)
    assert not passes(score("a", 10.0, 1.0, competitor=(6.0, 3.5)), RULE)   # 6 < 2 x 3.5
    assert passes(score("a", 10.0, 1.0, competitor=(6.0, 2.5)), RULE)


def test_over_dispersion_widens_every_se():
    # a 10-nat gain 3 SE away is significant for a model that fits the held-out data to the noise level, not for
    # one leaving a mean squared whitened residual of 9 (SE x 3)
    assert passes(score("a", 10.0, 3.0, dispersion=1.0), RULE)
    assert not passes(score("a", 10.0, 3.0, dispersion=9.0), RULE)
    assert passes(score("a", 10.0, 1.0, dispersion=0.2), RULE)   # under-dispersion never shrinks an SE


def test_ambiguity_set_uses_the_pairwise_measurement_se():
    best = score("a", 50.0, 5.0, gradient=[0, 0, 0, 0, 0])
    close = score("b", 45.0, 5.0, gradient=[3, 0, 0, 0, 0])    # 5 below the best, pairwise SE 3: within 2 SE
    far = score("c", 20.0, 5.0, gradient=[0, 4, 0, 0, 0])      # 30 below, SE 4: outside
    failing = score("d", 49.0, 30.0)                           # 1 below, pairwise SE 0: separated
    assert [s.name for s in ambiguity_set([far, close, best, failing], RULE)] == ["a", "b"]
    assert ambiguity_set([failing], RULE) == []


def test_unseparated_candidates_share_the_set_even_if_they_fail_alone():
    # the null case: scores 3351 / 3288 / 2643 nats within a few percent, one passing; with a held-out
    # mean squared residual of 60 the dispersion-corrected pairwise SE (sqrt(60) x 10 = 77) does not separate the
    # first two, and the second joins the set although its own strength test fails
    best = score("capillary_pressure", 3351.0, 5.0, gradient=[0, 0, 0, 0, 0], dispersion=60.0)
    second = score("inaccessible_pore_volume", 3288.0, 5.0, gradient=[10, 0, 0, 0, 0], strength_z=1.0,
                   dispersion=60.0)
    third = score("dispersion", 2643.0, 5.0, gradient=[0, 10, 0, 0, 0], dispersion=60.0)
    assert not passes(second, RULE)
    assert [s.name for s in ambiguity_set([third, second, best], RULE)] == ["capillary_pressure",
                                                                            "inaccessible_pore_volume"]
    unphysical = score("x", 3350.0, 5.0, physical=False, dispersion=60.0)
    assert "x" not in [s.name for s in ambiguity_set([best, unphysical], RULE)]


def test_verdicts():
    assert verdict([["a"]], True, 0.8, [], RULE) == ("effect", ["a"])
    assert verdict([["a", "b"]], True, 0.8, [], RULE) == ("ambiguous", ["a", "b"])
    assert verdict([["a"], ["b", "c"]], True, 0.9, [], RULE) == ("ambiguous", ["a"])
    assert verdict([["a"]], True, 0.3, [], RULE) == ("out_of_catalogue", [])   # helps, closes < half the gap
    assert verdict([["a"]], False, float("nan"), [], RULE) == ("none", [])  # a gain only out of sample
    # physical candidates close the calibration gap but none predicts the held-out flood better than the base
    # and the competitors: the gap is real, not attributable
    assert verdict([], True, 0.0, ["a", "b"], RULE) == ("unattributed", [])
    assert verdict([], True, 0.0, [], RULE) == ("out_of_catalogue", [])
    assert verdict([], False, 0.0, [], RULE) == ("none", [])
    # a gap found only by the targeted test (base misfit below its noise expectation): no fraction to close
    assert verdict([["a"]], True, float("nan"), [], RULE) == ("effect", ["a"])


def test_targeted_test_holds_its_level_and_finds_a_one_direction_gap():
    """Reference: a linear Gaussian model simulated here. Under a base model that holds, the K candidates'
    misfit drops are the squared projections of white noise on K unit directions (exactly chi^2_1 each); the
    Bonferroni-adjusted test must reject at most alpha of the time (the directions here are correlated, which
    makes Bonferroni conservative). With a gap along one direction of size 5 (a chi^2 drop of about 25) among
    n = 70 points, the omnibus chi^2_70 test is weak while the targeted test rejects nearly always."""
    from scipy.stats import chi2
    rng = np.random.default_rng(3)
    n, k, alpha, draws = 70, 11, 0.01, 20000
    directions = rng.standard_normal((k, n)) + 0.8 * rng.standard_normal(n)  # correlated candidate directions
    directions /= np.linalg.norm(directions, axis=1, keepdims=True)
    noise = rng.standard_normal((draws, n))
    null = [targeted_pvalue(list((directions @ e) ** 2), k) for e in noise]
    rate = np.mean(np.array(null) < alpha)
    assert rate <= alpha + 3 * np.sqrt(alpha * (1 - alpha) / draws)
    gap = 5.0 * directions[2]
    targeted = np.mean([targeted_pvalue(list((directions @ (e + gap)) ** 2), k) < alpha for e in noise[:2000]])
    omnibus = np.mean([chi2.sf(np.sum((e + gap) ** 2), n) < alpha for e in noise[:2000]])
    assert targeted > 0.9 and omnibus < 0.5
    assert targeted_pvalue([], 11) == 1.0 and targeted_pvalue([float("nan")], 11) == 1.0
