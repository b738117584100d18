"""The conformance kit (``spflow.testing.check_stage``) over every built-in stage, on small inputs (a two-parameter
space, six design points, 10-cell forward runs, small budgets). A built-in stage is either checked here or excluded
with its reason; a stage added to spflow without either fails ``test_every_builtin_stage_is_checked_or_excluded``."""

from __future__ import annotations

import pytest
from builtin_stage_cases import CASES, Small

from spflow.core.plugins import get_registry
from spflow.testing import ConformanceError, check_stage

#: Built-in stages the kit does not run, and why.
EXCLUDED: dict[str, str] = {}

#: Contract gaps the kit found in built-in stages and that are not fixed yet: stage -> the checks that fail. The test
#: asserts exactly these fail, so a fix (or a new gap) shows up here.
KNOWN_GAPS: dict[str, set[str]] = {}


@pytest.fixture(scope="module")
def small():
    return Small()


def test_every_builtin_stage_is_checked_or_excluded():
    providers = get_registry().providers
    builtin = {name for name in get_registry().stages if providers["stage:" + name].startswith("spflow.")}
    assert builtin == set(CASES) | set(EXCLUDED)
    assert not set(CASES) & set(EXCLUDED)
    assert set(KNOWN_GAPS) <= set(CASES)


@pytest.mark.parametrize("name", sorted(CASES))
def test_builtin_stage_conforms(name, small):
    params, inputs, nan_as_missing = CASES[name](small)
    stage = get_registry().stage(name)
    if name not in KNOWN_GAPS:
        report = check_stage(stage, inputs, params=params, nan_as_missing=nan_as_missing)
        expected = {"declaration", "params", "runs", "output_schema", "output_units", "purity", "determinism",
                    "cache_round_trip"} - ({"output_schema"} if stage.output is None else set())
        assert expected <= set(report.passed)
        return
    with pytest.raises(ConformanceError) as caught:
        check_stage(stage, inputs, params=params, nan_as_missing=nan_as_missing)
    assert set(caught.value.failed) == KNOWN_GAPS[name], str(caught.value)
