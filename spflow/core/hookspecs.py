"""Every extension point of spflow, in one place (the plugin author's table of contents).

A plugin is a module or object with functions marked ``@spflow.hookimpl``; a third-party package exposes it through
the entry-point group ``spflow`` in its ``pyproject.toml``::

    [project.entry-points.spflow]
    myplugin = "mypackage.spflow_plugin"

Built-in stages and effects register through exactly these hooks (see ``spflow/plugins/builtin.py``).
The registration hooks take a ``register`` callable: a plugin calls it once per contribution and the host validates.

The lifecycle hooks (``spflow_run_start`` ... ``spflow_run_end``) are notifications: the executor calls them in the
process that called :func:`spflow.run` (progress reported by a stage running in a worker process or on a Dask worker
is relayed there), return values are ignored, and an installed plugin's hook that raises is reported with a
:class:`~spflow.core.errors.PluginWarning` and the run goes on. They may be called from several threads at once (a
relay thread delivers the progress of stages running elsewhere), so an implementation that keeps state locks it.
The built-in log (``spflow/plugins/run_log.py``) and progress report (``spflow/plugins/progress_report.py``) are
implementations of these hooks like any other.
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
        """Contribute stage classes: call ``register(StageSubclass)`` for each, or ``register("package.module:Class",
        name="stage_name")`` to declare one without importing its module (imported when the stage is first used, and
        then checked to be a Stage subclass with that ``name``; :mod:`spflow.core.class_table`).

        .. versionadded:: 0.1
        .. versionchanged:: 0.2 stages may be registered by reference.
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
    def spflow_register_commands(self, register):
        """Contribute ``spflow`` sub-commands: ``register(names, add_parser, run)`` with ``names`` the sub-command
        names the parser adds (a tuple), ``add_parser(subparsers)`` adding them to the CLI's ``argparse`` sub-parsers
        and ``run(args) -> int`` the exit status of one invocation (``args.command`` says which name was used). A name
        already taken (the core commands run, status, report, list, clean, or another plugin's) is refused.

        .. versionadded:: 0.2
        """

    @hookspec
    def spflow_register_surrogate_kinds(self, register):
        """Contribute surrogate kinds: ``register(SurrogateSubclass)`` for each, a subclass of
        :class:`spflow.plugins.surrogates.contract.Surrogate` with a unique class attribute ``kind``, or
        ``register("package.module:Class", kind="kind_name")`` to declare one without importing its module (imported
        when a surrogate of the kind is first loaded, then checked; :mod:`spflow.core.class_table`). A stored surrogate
        whose ``attrs["surrogate"]`` names that kind is then rebuilt by its ``from_dataset`` wherever spflow loads one
        (:func:`~spflow.plugins.surrogates.contract.load_surrogate`: validation, calibration, MCMC, figures).

        .. versionadded:: 0.2
        .. versionchanged:: 0.2 surrogate kinds may be registered by reference.
        """

    @hookspec
    def spflow_run_start(self, pipeline, to_run, cached, runner):
        """A run begins: ``pipeline`` (:class:`~spflow.core.pipeline.Pipeline`), the names of the nodes ``to_run``
        (in topological order) and of the nodes found ``cached``, and the ``runner`` (a
        :class:`~spflow.core.runners.Runner`) that will execute them. Called after planning, before any stage runs.

        .. versionadded:: 0.2
        """

    @hookspec
    def spflow_node_start(self, node, stage, cached):
        """Node ``node`` (its :class:`~spflow.core.stage.Stage` instance is ``stage``) begins: submitted to the runner
        (``cached=False``), or found in the store (``cached=True``: at planning, when another run stored it while
        this one waited for its lock, or when it is a twin of a node computed in this run).

        .. versionadded:: 0.2
        """

    @hookspec
    def spflow_node_progress(self, node, done, total, what):
        """The stage of ``node`` has done ``done`` of ``total`` units of ``what`` (e.g. ``"samples"``,
        ``"generations"``, ``"steps"``); reported through :meth:`~spflow.core.stage.StageContext.report_progress`
        (at most a few times a second, always at ``done == total``). ``total`` may be ``None`` when unknown.

        .. versionadded:: 0.2
        """

    @hookspec
    def spflow_node_end(self, node, stage, seconds, cached):
        """Node ``node`` finished and its result is in the store: computed in ``seconds`` of wall time
        (``cached=False``), or reused (``cached=True``, ``seconds=0.0``).

        .. versionadded:: 0.2
        """

    @hookspec
    def spflow_node_error(self, node, stage, error):
        """Node ``node`` failed: ``error`` is the :class:`~spflow.core.errors.StageError` (the stage raised or returned
        something its schema refuses) or :class:`~spflow.core.errors.CacheError` (its result could not be stored).
        The run stores the nodes still running, starts no new one, and raises the error after ``spflow_run_end``.

        .. versionadded:: 0.2
        """

    @hookspec
    def spflow_run_end(self, pipeline, result, error):
        """The run of ``pipeline`` is over: ``result`` is the :class:`~spflow.core.executor.RunResult` (its
        ``executed`` and ``cached`` lists as far as the run got); ``error`` is the exception about to be raised, or
        ``None`` on success (a ``KeyboardInterrupt`` is reported too).

        .. versionadded:: 0.2
        """
