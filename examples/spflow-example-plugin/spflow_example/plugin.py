"""The plugin module named by the ``spflow`` entry point: one hook implementation per kind of contribution."""

import spflow

from .breakthrough import Breakthrough
from .wettability import WETTABILITY_ALTERATION


@spflow.hookimpl
def spflow_register_stages(register):
    register(Breakthrough)


@spflow.hookimpl
def spflow_register_effects(register):
    register(WETTABILITY_ALTERATION)
