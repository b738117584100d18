"""The run's log: the lifecycle hooks written to the standard :mod:`logging` module (a built-in plugin).

Loggers: ``spflow.executor`` (what a run will do, and an interrupted run) and ``spflow.stage.<node>`` (a node
started, finished with its wall time, failed, or was found stored by another run meanwhile); records of cached nodes
are DEBUG. Nothing is shown unless the application configures logging (library etiquette); the ``spflow`` command
shows INFO and above on stderr (:mod:`spflow.core.console`). The ``(k/n)`` count assumes one run at a time per
process.
"""

from __future__ import annotations

import logging
import threading

from spflow.core.hookspecs import hookimpl

_LOG = logging.getLogger("spflow.executor")
_LOCK = threading.Lock()
_RUN: dict[str, object] = {"to_run": frozenset(), "done": 0}


def node_logger(node: str) -> logging.Logger:
    """The logger of a node's records: ``spflow.stage.<node>``."""
    return logging.getLogger(f"spflow.stage.{node}")


@hookimpl
def spflow_run_start(pipeline, to_run, cached, runner):
    with _LOCK:
        _RUN.update(to_run=frozenset(to_run), done=0)
    if to_run:
        _LOG.info("%s: %d node(s) to run, %d cached", pipeline.name, len(to_run), len(cached))
    _LOG.debug("%s: runner %r", pipeline.name, runner)


@hookimpl
def spflow_node_start(node, stage, cached):
    if not cached:
        node_logger(node).info("%s: running %s ...", node, stage.name)
    elif node in _RUN["to_run"]:  # type: ignore[operator]
        node_logger(node).info("%s: computed meanwhile by another run; reused", node)
    else:
        node_logger(node).debug("%s: %s result reused from the cache", node, stage.name)


@hookimpl
def spflow_node_end(node, stage, seconds, cached):
    if cached:
        return
    with _LOCK:
        _RUN["done"] = done = int(_RUN["done"]) + 1  # type: ignore[call-overload]
        total = len(_RUN["to_run"])  # type: ignore[arg-type]
    node_logger(node).info("(%d/%d) %s: ran %s in %.2f s", done, total, node, stage.name, seconds)


@hookimpl
def spflow_node_error(node, stage, error):
    node_logger(node).error("%s: %s failed: %s", node, stage.name, error)


@hookimpl
def spflow_run_end(pipeline, result, error):
    if error is not None and not isinstance(error, Exception):
        _LOG.warning("%s: interrupted (%s) after %d node(s) executed; finished nodes are stored", pipeline.name,
                     type(error).__name__, len(result.executed))
