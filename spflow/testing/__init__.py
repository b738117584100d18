"""Conformance kit for stages, surrogate kinds and samplers, built-in or from a plugin (docs/plugins.md, "Check your
plugin").

``check_stage``, ``check_surrogate`` and ``check_sampler`` each run a list of named checks and return a
:class:`ConformanceReport` of those that passed, or raise one :class:`ConformanceError` (a
:class:`~spflow.core.errors.SpflowError`) listing every failed check with the contract it enforces and the fix.
:mod:`spflow.testing.small_inputs` builds tiny inputs for the built-in ports (a two-parameter space, a few design
points, 10-cell forward runs) so that the checks run in seconds.
"""

from .checklist import ConformanceError, ConformanceReport
from .sampler_checks import SAMPLER_CHECKS, check_sampler
from .stage_checks import STAGE_CHECKS, check_stage
from .surrogate_checks import SURROGATE_CHECKS, check_surrogate

__all__ = ["check_stage", "check_surrogate", "check_sampler", "ConformanceError", "ConformanceReport", "STAGE_CHECKS",
           "SURROGATE_CHECKS", "SAMPLER_CHECKS"]
