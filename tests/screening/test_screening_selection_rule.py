"""The threshold / top-k selection rule on the analytic total indices of the Sobol' G-function (no estimation)."""

import numpy as np
import pytest
from oracles.sensitivity_benchmarks import G_STANDARD_A, sobol_g_moments

from spflow.core.errors import ParameterError
from spflow.plugins.screening.selection import SelectionRule
from spflow.plugins.screening.sobol_screening import SobolScreening

NAMES = np.array([f"x{i + 1}" for i in range(G_STANDARD_A.size)])
ST = sobol_g_moments(G_STANDARD_A)["ST"]  # 0.787, 0.242, 0.034, 0.0105, 1e-4 x 4
# two "sub-models": the important inputs split across them, inert ones in both
GROUPS = np.array(["A", "B", "B", "A", "A", "B", "A", "B"])


def _picked(rule, groups=GROUPS):
    return NAMES[rule.apply(ST, groups)].tolist()


def test_threshold_alone_keeps_indices_at_or_above_it():
    assert _picked(SelectionRule(threshold=0.1)) == ["x1", "x2"]
    assert _picked(SelectionRule(threshold=0.01)) == ["x1", "x2", "x3", "x4"]
    assert _picked(SelectionRule(threshold=float(ST[2]))) == ["x1", "x2", "x3"]  # inclusive


def test_top_k_over_all_and_per_group():
    assert _picked(SelectionRule(threshold=0.0, top_k=3, top_k_scope="all")) == ["x1", "x2", "x3"]
    # per group: A = {x1, x4, x5, x7}, B = {x2, x3, x6, x8}
    assert _picked(SelectionRule(threshold=0.0, top_k=1)) == ["x1", "x2"]
    assert _picked(SelectionRule(threshold=0.0, top_k=2)) == ["x1", "x2", "x3", "x4"]


def test_and_or_combinations():
    # "and": top-2 per group but only if ST >= 0.02 -> x4 (0.0105) drops out
    assert _picked(SelectionRule(threshold=0.02, top_k=2, combine="and")) == ["x1", "x2", "x3"]
    # "or": at least the best of each group, plus anything above 0.03
    assert _picked(SelectionRule(threshold=0.5, top_k=1, combine="or")) == ["x1", "x2"]
    # x5 is the (tied) best of the all-inert group B: ties go to the first listed
    inert_group = np.array(["A", "A", "A", "A", "B", "B", "B", "B"])
    assert _picked(SelectionRule(threshold=0.03, top_k=1, combine="or"), inert_group) == ["x1", "x2", "x3", "x5"]


def test_rule_parameters_are_validated_by_the_stage():
    with pytest.raises(ParameterError, match="threshold"):
        SobolScreening(threshold=1.5)
    with pytest.raises(ParameterError, match="combine"):
        SobolScreening(combine="xor")
    with pytest.raises(ParameterError, match="top_k"):
        SobolScreening(top_k=-1)
