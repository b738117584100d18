"""Every extension point of spflow, in one place (the plugin author's table of contents).

A plugin is a module or object with functions marked ``@spflow.hookimpl``; a third-party package exposes it through
the entry-point group ``spflow`` in its ``pyproject.toml``::

    [project.entry-points.spflow]
    myplugin = "mypackage.spflow_plugin"

Built-in stages and effects register through exactly these hooks (see ``spflow/plugins/builtin.py``).
All hooks take a ``register`` callable: a plugin calls it once per contribution and the host validates.
"""

from __future__ import annotations

import pluggy

__all__ = ["hookspec", "hookimpl", "SpflowHookSpecs", "PROJECT_NAME"]

PROJECT_NAME = "spflow"
hookspec = pluggy.HookspecMarker(PROJECT_NAME)
hookimpl = pluggy.HookimplMarker(PROJECT_NAME)


class SpflowHookSpecs:
    """Hook specifications."""

    @hookspec
    def spflow_register_stages(self, register):
        """Contribute stage classes: call ``register(StageSubclass)`` for each.

        .. versionadded:: 0.1
        """

    @hookspec
    def spflow_register_effects(self, register):
        """Contribute forward-model effects (mechanisms a base model may lack): ``register(Effect(...))``.

        .. versionadded:: 0.1
        """

    @hookspec
    def spflow_register_hashers(self, register):
        """Contribute canonical hashers for extra types: ``register(type, func)`` with ``func(obj, h)``.

        .. versionadded:: 0.1
        """

    @hookspec
    def spflow_register_surrogate_kinds(self, register):
        """Contribute surrogate kinds: ``register(SurrogateSubclass)`` for each, a subclass of
        :class:`spflow.plugins.surrogates.contract.Surrogate` with a unique class attribute ``kind``. A stored surrogate
        whose ``attrs["surrogate"]`` names that kind is then rebuilt by its ``from_dataset`` wherever spflow loads one
        (:func:`~spflow.plugins.surrogates.contract.load_surrogate`: validation, calibration, MCMC, figures).

        .. versionadded:: 0.1
        """
