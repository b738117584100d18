"""The ready-made pipelines shipped with spflow, one module per pipeline, runnable by name from any directory.

Each module's docstring starts with the one line ``spflow list pipelines`` shows; the module defines ``pipeline``
(a :class:`~spflow.core.pipeline.Pipeline` or a function returning one, taking ``quick`` for its small-budget
profile) and optionally ``report(result, outdir)``. :mod:`spflow.core.pipeline_registry` finds them next to the
pipelines third-party packages contribute (entry-point group ``spflow.pipelines``) and the user's own files.
This package imports none of its modules: a pipeline is imported when it is run.
"""
