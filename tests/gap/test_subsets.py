"""The joint effect search on a linear toy built so that greedy forward selection provably fails: two effects
(A, B) cancel each other almost entirely on the calibration data, so neither alone is asked for there, while the
truth is A + B + C. Every fit, chi^2 and strength z below is closed-form linear least squares computed here."""

import numpy as np

from spflow.plugins.gap.predictive_scores import Predictive
from spflow.plugins.gap.subsets import SubsetFit, admissible, best_subset, forward_selection
from spflow.plugins.gap.verdict import Rule

RULE = Rule()
N_CAL, N_HELD = 60, 50


def unit(n, k):
    e = np.zeros(n)
    e[k] = 1.0
    return e


# calibration signatures: f_A = 10 e1, f_B = -10 e1 + 5 e2 (A + B leave only 5 e2), f_C = 8 e3, f_D = 6 e4
CAL = {"A": 10 * unit(N_CAL, 1), "B": -10 * unit(N_CAL, 1) + 5 * unit(N_CAL, 2), "C": 8 * unit(N_CAL, 3),
       "D": 6 * unit(N_CAL, 4)}
# held-out signatures (another schedule: A and B no longer cancel)
HELD = {"A": 10 * unit(N_HELD, 1), "B": 5 * unit(N_HELD, 2), "C": 8 * unit(N_HELD, 3), "D": 6 * unit(N_HELD, 4)}
TRUTH = ("A", "B", "C")
Y_CAL = sum(CAL[n] for n in TRUTH)
Y_HELD = sum(HELD[n] for n in TRUTH)


def evaluate(names):
    """Least squares of the calibration data on the signatures of ``names`` (unit noise), scored on held out."""
    names = tuple(names)
    if names:
        x = np.column_stack([CAL[n] for n in names])
        s = np.linalg.lstsq(x, Y_CAL, rcond=None)[0]
        sd = np.sqrt(np.diag(np.linalg.inv(x.T @ x)))
        pred = np.column_stack([HELD[n] for n in names]) @ s
        fitted = x @ s
    else:
        s, sd, pred, fitted = np.zeros(0), np.zeros(0), np.zeros(N_HELD), np.zeros(N_CAL)
    r = fitted - Y_CAL
    w = pred - Y_HELD
    return SubsetFit(names, float(r @ r), dict(zip(names, s)), dict(zip(names, s / sd)),
                     {n: bool(0.2 <= v <= 5.0) for n, v in zip(names, s)}, Predictive(-0.5 * w**2, w, w))


def test_the_toy_defeats_greedy_selection():
    # neither A nor B alone is asked for by the calibration data (chi^2 drops 0 and 5 < 6.63) ...
    base = evaluate(())
    assert base.chi2 - evaluate(("A",)).chi2 < RULE.min_chi2_drop
    assert base.chi2 - evaluate(("B",)).chi2 < RULE.min_chi2_drop
    # ... nor on top of C, so the greedy path stops at C alone
    assert forward_selection(["A", "B", "C", "D"], evaluate, RULE) == ("C",)


def test_the_subset_search_finds_the_three_planted_effects():
    result = best_subset(["A", "B", "C", "D"], evaluate, RULE, max_size=3)
    assert result.chosen == TRUTH
    fitted = evaluate(result.chosen)
    np.testing.assert_allclose([fitted.strengths[n] for n in TRUTH], [1.0, 1.0, 1.0], atol=1e-12)
    # backward elimination: every member earns its place; a spurious fourth effect is never admissible with them
    assert admissible(TRUTH, evaluate, RULE)
    assert not admissible(("A", "B", "D"), evaluate, RULE)
    assert not admissible(("A", "C"), evaluate, RULE)
    # every subset of at most three of the four is fitted once: C(4,1) + C(4,2) + C(4,3) plus the base
    assert len(result.fits) == 4 + 6 + 4 + 1


def test_a_competitor_that_predicts_as_well_blocks_the_set():
    # a competitor predicting the held-out data as well as the truth leaves no set admissible
    perfect = Predictive(np.zeros(N_HELD), np.zeros(N_HELD), np.zeros(N_HELD))
    assert best_subset(["A", "B", "C"], evaluate, RULE, max_size=3, competitors=[perfect]).chosen == ()
