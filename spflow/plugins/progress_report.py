"""Progress of running nodes with elapsed time and ETA: ``spflow_node_progress`` -> log records (a built-in plugin).

Each report of a node becomes a record of its logger ``spflow.stage.<node>`` carrying a :class:`Progress` as
``record.progress``: INFO at milestones (the first and the last report, then whenever another 10 % is done or
:data:`MILESTONE_SECONDS` passed since the previous milestone), DEBUG in between; a node's end adds a DEBUG record
with ``finished=True``. An ordinary log handler at INFO thus shows about ten lines per node; the terminal display of
the ``spflow`` command (:mod:`spflow.core.console`) redraws a live bar from every record.

The ETA is linear in the rate since the node's first report (so that starting a worker process or loading inputs
does not count as work): (now - first report) / (done - done at the first report) x (total - done).
"""

from __future__ import annotations

import logging
import threading
import time
from dataclasses import dataclass

from spflow.core.hookspecs import hookimpl
from spflow.plugins.run_log import node_logger

#: Longest interval between two INFO progress lines of one node.
MILESTONE_SECONDS = 5.0
#: Fraction of the total between two INFO progress lines of one node.
MILESTONE_FRACTION = 0.1


def clock(seconds: float) -> str:
    """``m:ss`` (or ``h:mm:ss``) of a duration."""
    minutes, secs = divmod(int(round(seconds)), 60)
    hours, minutes = divmod(minutes, 60)
    return f"{hours}:{minutes:02d}:{secs:02d}" if hours else f"{minutes}:{secs:02d}"


@dataclass(frozen=True)
class Progress:
    """How far a node has got: ``done`` of ``total`` (None: unknown) ``what``, ``elapsed`` seconds since it started,
    ``eta`` seconds still to go (None until something is done or without a total)."""

    node: str
    done: int
    total: int | None
    what: str
    elapsed: float
    eta: float | None
    finished: bool = False

    @property
    def fraction(self) -> float | None:
        return min(1.0, self.done / self.total) if self.total else None

    def describe(self) -> str:
        """``45/100 samples (45 %), 0:12 elapsed, ETA 0:15``."""
        count = f"{self.done}/{self.total} {self.what} ({100 * self.done // self.total} %)" if self.total \
            else f"{self.done} {self.what}"
        eta = f", ETA {clock(self.eta)}" if self.eta is not None and self.done != self.total else ""
        return f"{count}, {clock(self.elapsed)} elapsed{eta}"


@dataclass
class _Node:
    started: float
    first_time: float = -1.0
    first_done: int = 0
    milestone_time: float = -1.0
    milestone_done: int = 0
    last: Progress | None = None


_LOCK = threading.Lock()
_NODES: dict[str, _Node] = {}


@hookimpl
def spflow_node_start(node, stage, cached):
    if not cached:
        with _LOCK:
            _NODES[node] = _Node(time.monotonic())


@hookimpl
def spflow_node_progress(node, done, total, what):
    now = time.monotonic()
    with _LOCK:
        state = _NODES.setdefault(node, _Node(now))
        first = state.milestone_time < 0
        if first:
            state.first_time, state.first_done = now, done
        rate = (now - state.first_time) / (done - state.first_done) if done > state.first_done else None
        eta = rate * (total - done) if rate is not None and total else None
        progress = Progress(node, done, total, what, now - state.started, eta)
        milestone = (first or done == total or now - state.milestone_time >= MILESTONE_SECONDS
                     or bool(total) and (done - state.milestone_done) >= MILESTONE_FRACTION * total)
        if milestone:
            state.milestone_time, state.milestone_done = now, done
        state.last = progress
    node_logger(node).log(logging.INFO if milestone else logging.DEBUG, "%s: %s", node, progress.describe(),
                          extra={"progress": progress})


def _finished(node: str) -> None:
    with _LOCK:
        state = _NODES.pop(node, None)
    if state is not None and state.last is not None:
        last = state.last
        done = Progress(node, last.done, last.total, last.what, time.monotonic() - state.started, None, finished=True)
        node_logger(node).debug("%s: progress finished", node, extra={"progress": done})


@hookimpl
def spflow_node_end(node, stage, seconds, cached):
    _finished(node)


@hookimpl
def spflow_node_error(node, stage, error):
    _finished(node)
