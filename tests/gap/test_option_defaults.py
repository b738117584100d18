"""The diagnose stage's option parameters declare the same defaults as the diagnosis's ``Options``.

The stage keeps its own declarations (``spflow list`` shows them without importing the diagnosis), so the two sets
of defaults are written twice; a default changed in one place only (as ``predictive_centre`` had to be changed in
both) would make the stage and the Python API diagnose differently.
"""

from dataclasses import fields

import pytest
from scipy.stats import chi2

from spflow.plugins.gap.diagnosis import Options
from spflow.plugins.gap.stage import OPTION_PARAMS, options_from


def test_stage_defaults_are_the_options_defaults():
    from_stage = options_from({name: p.default for name, p in OPTION_PARAMS.items()})
    reference = Options()
    for f in fields(Options):
        if f.name != "rule":
            assert getattr(from_stage, f.name) == getattr(reference, f.name), f.name
    # the rule's likelihood-ratio threshold is the chi^2_1 quantile at alpha (Options writes it rounded)
    assert from_stage.rule.min_chi2_drop == pytest.approx(chi2.isf(reference.alpha, 1))
    assert reference.rule.min_chi2_drop == pytest.approx(chi2.isf(reference.alpha, 1), abs=1e-3)
    for name in ("min_delta", "se_factor", "closed_fraction", "physical_tolerance"):
        assert getattr(from_stage.rule, name) == getattr(reference.rule, name), name
