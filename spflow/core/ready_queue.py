"""When the nodes of a run start: a ready queue within a worker budget.

A node is *ready* when every node it depends on has its result stored. Ready nodes start in the given priority
order (the executor's: topological generation, then name -- the order of the former generation-by-generation
scheduler when nodes run one at a time) as long as
the runner has a free node slot and the worker budget ``jobs`` has room; the workers still free when a node starts
are split among the nodes starting at that moment, each node's share being the ``n_jobs`` of its own parallelism
(a node starting alone on an idle budget gets all of it, nodes started side by side get one each). A finished node
frees its share and makes its successors ready at once: one slow node holds back only its own descendants.

Locks (the executor's per-key locks, through :class:`NodeOps`) are taken without waiting; a ready node whose lock
another run holds is retried every :data:`LOCK_POLL` seconds while other nodes run, and waited for only when nothing
runs, so a run never waits for a lock while holding another (two runs cannot deadlock). After a failure no new node
starts; the running ones finish and are stored, then the failure of the first node by name is raised.
"""

from __future__ import annotations

import bisect
from collections.abc import Callable
from concurrent.futures import FIRST_COMPLETED, Future, wait
from dataclasses import dataclass

import networkx as nx

__all__ = ["NodeOps", "drive", "LOCK_POLL"]

#: Seconds between attempts at the locks of ready nodes another run holds, while this run has nodes running.
LOCK_POLL = 0.5


@dataclass
class NodeOps:
    """What the executor does to a node at each step of its life."""

    #: take the node's lock without waiting; False if another run holds it
    try_lock: Callable[[str], bool]
    #: wait for the node's lock (called only while holding no other lock)
    lock: Callable[[str], None]
    unlock: Callable[[str], None]
    #: with the lock held: False if the result is already there (another run stored it; the node counts as done)
    needed: Callable[[str], bool]
    #: start the node with ``n_jobs`` workers for its own parallelism; the Future yields what ``land`` takes
    launch: Callable[[str, int], Future]
    #: store a finished node's result; raises the node's failure
    land: Callable[[str, Future], None]


def _shares(free: int, count: int) -> list[int]:
    """``free`` workers split among ``count`` nodes, as evenly as possible, at least one each."""
    base, extra = divmod(max(free, count), count)
    return [base + (k < extra) for k in range(count)]


def drive(graph: nx.DiGraph, priority: list[str], jobs: int, slots: int, ops: NodeOps) -> None:
    """Run every node of ``graph`` (edges: dependencies), ready nodes in the order of ``priority``, at most
    ``slots`` at once within ``jobs`` workers."""
    position = {name: k for k, name in enumerate(priority)}
    missing = {name: graph.in_degree(name) for name in graph}
    ready = sorted((name for name, n in missing.items() if n == 0), key=position.__getitem__)
    running: dict[Future, tuple[str, int]] = {}
    failures: list[tuple[str, Exception]] = []

    def stored(name: str) -> None:
        for successor in graph.successors(name):
            missing[successor] -= 1
            if missing[successor] == 0:
                bisect.insort(ready, successor, key=position.__getitem__)

    def start_ready() -> bool:
        """Start what the budget allows; True if a ready node was left because another run holds its lock."""
        free = jobs - sum(share for _, share in running.values())
        room = min(slots - len(running), free)
        picked: list[str] = []
        for name in list(ready):
            if len(picked) >= room:
                break
            if ops.try_lock(name):
                picked.append(name)
                ready.remove(name)
        locked_out = len(picked) < room and bool(ready)
        if not picked and not running and ready:
            ops.lock(ready[0])  # nothing of ours runs and every ready node is another run's: wait, holding nothing
            picked.append(ready.pop(0))
        for name, share in zip(picked, _shares(free, len(picked)) if picked else []):
            try:
                if not ops.needed(name):
                    ops.unlock(name)
                    stored(name)
                    continue
                running[ops.launch(name, share)] = (name, share)
            except Exception as exc:
                ops.unlock(name)
                failures.append((name, exc))
        return locked_out

    try:
        while ready or running:
            locked_out = start_ready() if not failures else False
            if failures and not running:
                break
            if not running:
                continue
            done, _ = wait(list(running), timeout=LOCK_POLL if locked_out else None, return_when=FIRST_COMPLETED)
            for future in sorted(done, key=lambda f: running[f][0]):
                name, _ = running.pop(future)
                try:
                    ops.land(name, future)
                except Exception as exc:  # the others still finish and are stored
                    failures.append((name, exc))
                else:
                    stored(name)
                finally:
                    ops.unlock(name)
    finally:  # e.g. KeyboardInterrupt: hand back the locks of what was running (nothing of it is stored)
        for name, _ in running.values():
            ops.unlock(name)
    if failures:
        raise min(failures, key=lambda item: item[0])[1]
