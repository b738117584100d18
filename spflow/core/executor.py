"""Run a pipeline: plan from provenance keys, reuse cached results, execute the rest through a ready queue.

* Keys are computed for every node before anything runs (see :mod:`spflow.core.provenance`).
* A node whose key is in the store is not executed if the entry passes its checksum, records that key and stage, and
  matches the stage's output schema (dims, variables, dtypes, units: read without loading the arrays); any other
  entry is discarded with a :class:`~spflow.core.errors.CacheIntegrityWarning` and recomputed.
* Nodes to execute start as soon as their inputs are stored, within the worker budget ``jobs``
  (:mod:`spflow.core.ready_queue`); a node's own parallelism (``ctx.parallel()``) gets the workers that were free
  when it started. Where a node runs -- this process, threads, loky processes, a Dask cluster -- is the runner's
  business (:mod:`spflow.core.runners`); results and keys do not depend on it.
* Runs sharing a cache coordinate through per-key locks: a node is computed under its key's lock, and a run that
  finds the lock taken computes its other ready nodes first, then waits and reuses what the other run stored. A run
  never waits for a lock while holding another, so two runs cannot deadlock.
* Nodes with the same key (the same stage, params and upstream data, e.g. one node copied into two included
  sub-pipelines) are computed once per run; the others read the stored result.
* Each finished node is validated and written to the store as soon as it completes, so an exception or
  KeyboardInterrupt loses nothing that finished; the next run resumes from there. A failed write (full or read-only
  disk) stops the run with a :class:`~spflow.core.errors.CacheError` naming the node, the cache and the cause.
* The per-pipeline manifest (behind ``status``'s explanations) is written only when it changes, and best-effort: a
  failure is a :class:`~spflow.core.errors.CacheWarning`. A fully cached run writes nothing, so it works on a
  read-only cache.
* Every step calls the lifecycle hooks (``spflow_run_start``, ``spflow_node_start``, ``spflow_node_progress``,
  ``spflow_node_end``, ``spflow_node_error``, ``spflow_run_end``: :mod:`spflow.core.hookspecs`); the executor
  prints nothing itself -- its log and progress display are built-in plugins of those hooks.
"""

from __future__ import annotations

import os
import time
import warnings
from collections.abc import Callable, Iterable, Iterator, Mapping
from concurrent.futures import Future
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import networkx as nx
import xarray as xr

from .cache import Store
from .cf_metadata import CONVENTIONS, claims_cf, note_units
from .errors import CacheError, CacheIntegrityWarning, CacheWarning, PipelineError, SchemaError, StageError
from .pipeline import Pipeline
from .plugins import get_registry
from .provenance import key_of, provenance, stale_reasons
from .ready_queue import NodeOps, drive
from .runners import Runner, Workers, runner_for
from .stage import Stage, StageContext

__all__ = ["run", "status", "RunResult", "NodeStatus"]


@dataclass
class _Plan:
    pipeline: Pipeline
    stages: dict[str, Stage]
    prov: dict[str, dict[str, Any]]
    keys: dict[str, str]
    order: list[str]
    graph: nx.DiGraph


def _instantiate(pipeline: Pipeline) -> dict[str, Stage]:
    """Create every node's stage with validated params and check its wiring — before any work."""
    from spflow.plugins.data import DataStage

    registry = get_registry()
    stages: dict[str, Stage] = {}
    for node in pipeline.nodes.values():
        if node.stage == "data":
            if node.dataset is None:
                raise PipelineError(f"node {node.name!r}: stage 'data' nodes are added with Pipeline.add_data()")
            stages[node.name] = DataStage.holding(node.dataset)
            continue
        cls = registry.stage(node.stage)
        stages[node.name] = cls(**node.params)
        unknown = sorted(set(node.inputs) - set(cls.inputs))
        if unknown:
            raise PipelineError(
                f"node {node.name!r}: stage {cls.name!r} has no input port {unknown[0]!r}; ports: {sorted(cls.inputs)}"
            )
        missing = sorted(set(cls.inputs) - set(node.inputs) - set(cls.optional_inputs))
        if missing:
            raise PipelineError(f"node {node.name!r}: input port {missing[0]!r} of stage {cls.name!r} is not wired")
    return stages


def _plan(pipeline: Pipeline) -> _Plan:
    graph = pipeline.graph()
    order = pipeline.order()
    stages = _instantiate(pipeline)
    prov: dict[str, dict[str, Any]] = {}
    keys: dict[str, str] = {}
    for name in order:
        inputs = {port: keys[up] for port, up in pipeline.nodes[name].inputs.items()}
        prov[name] = provenance(stages[name], inputs)
        keys[name] = key_of(prov[name])
    return _Plan(pipeline, stages, prov, keys, order, graph)


@dataclass
class RunResult(Mapping):
    """Outputs of a run, loaded from the store on access: ``result["node"]`` is that node's Dataset."""

    store: Store
    keys: dict[str, str]
    executed: list[str] = field(default_factory=list)
    cached: list[str] = field(default_factory=list)
    _memo: dict[str, xr.Dataset] = field(default_factory=dict, repr=False)

    def __getitem__(self, node: str) -> xr.Dataset:
        if node not in self.keys:
            raise KeyError(f"node {node!r} was not part of this run; available: {sorted(self.keys)}")
        if node not in self._memo:
            self._memo[node] = self.store.load(self.keys[node])
        return self._memo[node]

    def __iter__(self) -> Iterator[str]:
        return iter(self.keys)

    def seconds(self, node: str) -> float | None:
        """Wall seconds of the run that computed ``node``'s stored result (from its store record, kept out of the
        result itself so that run timing does not change a result); ``None`` if the record has no time."""
        if node not in self.keys:
            raise KeyError(f"node {node!r} was not part of this run; available: {sorted(self.keys)}")
        seconds = self.store.record(self.keys[node]).get("seconds")
        return None if seconds is None else float(seconds)

    def scoped(self, prefix: str) -> RunResult:
        """The results of the nodes included as ``<prefix>.<node>`` (``Pipeline.include``) under their own names,
        plus the unprefixed (shared) nodes -- what the included pipeline's own ``report`` expects."""
        lead = f"{prefix}."
        rename = {n: n[len(lead):] for n in self.keys if n.startswith(lead)}
        rename.update({n: n for n in self.keys if "." not in n and n not in rename.values()})
        return RunResult(self.store, {new: self.keys[old] for old, new in rename.items()},
                         [rename[n] for n in self.executed if n in rename],
                         [rename[n] for n in self.cached if n in rename])

    def __len__(self) -> int:
        return len(self.keys)


def _selected(pipeline: Pipeline, until: Iterable[str] | str | None, only: Iterable[str] | str | None) -> set[str]:
    if isinstance(until, str):
        until = [until]
    if isinstance(only, str):
        only = [only]
    if until and only:
        raise PipelineError("use either until or only, not both")
    if only:
        for n in only:
            pipeline._node(n)
        return set(only)
    if until:
        return pipeline.upstream_of(until)
    return set(pipeline.nodes)


def _execute(stage: Stage, ctx: StageContext, inputs: dict[str, xr.Dataset],
             origin_pid: int) -> tuple[xr.Dataset, float, list]:
    """Run one stage (wherever the runner put it) and return its output, wall time and, when it ran in another
    process than ``origin_pid`` (the run's), the warnings it raised as ``(category, message, filename, lineno)``: a
    worker process's warnings would otherwise never reach the user; :func:`_reemit` raises them again in the run's
    process. In the run's own process (sequential and thread runners) warnings go out as they happen
    (``warnings.catch_warnings`` is not thread-safe)."""
    t0 = time.perf_counter()
    if os.getpid() == origin_pid:
        return stage.run(ctx, **inputs), time.perf_counter() - t0, []
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        out = stage.run(ctx, **inputs)
    seen = list(dict.fromkeys((w.category, str(w.message), w.filename, w.lineno) for w in caught))
    return out, time.perf_counter() - t0, seen


def _reemit(caught: list) -> None:
    """Raise the warnings a stage raised (once each, where it raised them) under this process's warning filters."""
    for category, message, filename, lineno in caught:
        warnings.warn_explicit(message, category, filename, lineno)


def run(pipeline: Pipeline, *, cache: str | Path = ".spflow", jobs: int = 1, backend: str | Runner = "loky",
        scheduler: str | None = None, until: Iterable[str] | str | None = None,
        only: Iterable[str] | str | None = None, force: Iterable[str] | str = (), verbose: bool = False) -> RunResult:
    """Run ``pipeline`` and return its results (a mapping node -> Dataset).

    Parameters
    ----------
    cache: directory of the result store.
    jobs: worker budget (nodes side by side, and the inner parallelism of nodes started on free workers).
    backend: a :class:`~spflow.core.runners.Runner`, or the name of one (:data:`~spflow.core.runners.BACKENDS`):
        ``loky`` (processes, default), ``threads``, ``sequential`` or ``dask`` (with ``scheduler`` = address).
    until: run only these nodes and their ancestors.
    only: run only these nodes; their inputs must already be in the cache.
    force: recompute these nodes and everything downstream of them even if cached.
    verbose: passed to the stages (``StageContext.verbose``: a stage may print its own findings). What the run
        does is logged (``logging``, loggers ``spflow.executor`` and ``spflow.stage.<node>``), shown only if the
        application configures logging, as the ``spflow`` command does.
    """
    if isinstance(jobs, bool) or not isinstance(jobs, int) or jobs < 1:
        raise PipelineError(f"jobs must be an integer >= 1 (not a bool), got {jobs!r}")
    runner = runner_for(backend, scheduler)
    plan = _plan(pipeline)
    notify = get_registry().notify
    store = Store(cache)
    selected = _selected(pipeline, until, only)
    forced = pipeline.downstream_of([force] if isinstance(force, str) else force) & selected
    order = [n for n in plan.order if n in selected]

    to_run: list[str] = []
    twins: dict[str, str] = {}  # node -> the node computing the same key in this run
    first_with: dict[str, str] = {}
    result = RunResult(store, {n: plan.keys[n] for n in order})
    for name in order:
        key = plan.keys[name]
        if key in first_with:
            twins[name] = first_with[key]
            continue
        if name not in forced and store.has(key):
            problem = _entry_problem(store, key, plan.stages[name])
            if problem is None:
                result.cached.append(name)
                continue
            warnings.warn(f"cache entry {key[:12]} of node {name!r} {problem}; discarding and recomputing",
                          CacheIntegrityWarning, stacklevel=2)
        to_run.append(name)
        first_with[key] = name
    manifest = _Manifest(store, pipeline.name)
    manifest.note({name: plan.prov[name] for name in result.cached})

    if only:
        for name in to_run:
            for port, up in pipeline.nodes[name].inputs.items():
                if up not in selected and not store.verify(plan.keys[up]):
                    raise PipelineError(
                        f"--only {name!r}: its input {port!r} (node {up!r}) is not in the cache; run without only first"
                    )

    notify("spflow_run_start", pipeline=pipeline, to_run=list(to_run), cached=list(result.cached), runner=runner)
    error: BaseException | None = None
    try:
        for name in result.cached:
            _reused(notify, name, plan.stages[name])
        ops = _NodeOps(plan, store, manifest, result, forced, notify, runner, verbose)
        if to_run:  # a fully cached run starts no workers (no process pool, no connection to a Dask scheduler)
            with runner.started(jobs, ops.progress(notify)) as workers:
                ops.workers = workers
                graph = _run_graph(plan.graph, to_run, twins)
                priority = [n for generation in nx.topological_generations(graph) for n in sorted(generation)]
                drive(graph, priority, jobs, runner.node_slots(jobs),
                      NodeOps(ops.try_lock, ops.lock, ops.unlock, ops.needed, ops.launch, ops.land))
        computed_twins = [n for n in twins if twins[n] in result.executed]
        result.cached += computed_twins
        manifest.note({name: plan.prov[name] for name in computed_twins})
        for name in computed_twins:
            _reused(notify, name, plan.stages[name])
    except BaseException as exc:
        error = exc
        raise
    finally:
        notify("spflow_run_end", pipeline=pipeline, result=result, error=error)
    return result


def _reused(notify: Callable[..., None], name: str, stage: Stage) -> None:
    notify("spflow_node_start", node=name, stage=stage, cached=True)
    notify("spflow_node_end", node=name, stage=stage, seconds=0.0, cached=True)


class _NodeOps:
    """The executor's side of each step of a node's life (:class:`~spflow.core.ready_queue.NodeOps`): its key's
    lock, the look for a result another run stored, loading and checking its inputs, submitting it to the runner,
    checking and storing its output; with the lifecycle hooks at each step."""

    def __init__(self, plan: _Plan, store: Store, manifest: _Manifest, result: RunResult, forced: set[str],
                 notify: Callable[..., None], runner: Runner, verbose: bool):
        self.plan, self.store, self.manifest, self.result, self.runner = plan, store, manifest, result, runner
        self.forced, self.notify, self.verbose = forced, notify, verbose
        self.memory: dict[str, xr.Dataset] = {}
        self.workers: Workers | None = None

    @staticmethod
    def progress(notify: Callable[..., None]) -> Callable[[str, int, int | None, str], None]:
        def report(node: str, done: int, total: int | None, what: str) -> None:
            notify("spflow_node_progress", node=node, done=done, total=total, what=what)
        return report

    def _acquire(self, name: str, blocking: bool) -> bool:
        try:
            return self.store.acquire(self.plan.keys[name], blocking=blocking,
                                      waiting=f"{name}: another run is computing this node")
        except OSError as exc:
            raise CacheError(f"node {name!r}: cannot lock its cache entry in {self.store.root}: {exc}") from exc

    def try_lock(self, name: str) -> bool:
        return self._acquire(name, blocking=False)

    def lock(self, name: str) -> None:
        self._acquire(name, blocking=True)

    def unlock(self, name: str) -> None:
        self.store.release(self.plan.keys[name])

    def needed(self, name: str) -> bool:
        """With the node's lock held: False if another run stored a good entry meanwhile (then it is reused);
        otherwise clear any entry in the way (forced, or failing the checks) and return True."""
        key, stage = self.plan.keys[name], self.plan.stages[name]
        try:
            if self.store.has(key):
                if name not in self.forced and _entry_problem(self.store, key, stage) is None:
                    self.result.cached.append(name)
                    self.manifest.note({name: self.plan.prov[name]})
                    _reused(self.notify, name, stage)
                    return False
                self.store.discard(key)
        except OSError as exc:
            raise CacheError(f"node {name!r}: cannot replace its cache entry in {self.store.root}: {exc}") from exc
        return True

    def _inputs(self, name: str) -> dict[str, xr.Dataset]:
        """The node's inputs (from memory, else loaded from the store), checked against its stage's input schemas."""
        stage = self.plan.stages[name]
        inputs = {}
        for port, up in self.plan.pipeline.nodes[name].inputs.items():
            if up not in self.memory:
                self.memory[up] = self.store.load(self.plan.keys[up])
            inputs[port] = self.memory[up]
            schema = stage.inputs.get(port)
            if schema is not None:
                schema.validate(inputs[port], stage=stage.name, port=port)
        return inputs

    def launch(self, name: str, n_jobs: int) -> Future:
        stage = self.plan.stages[name]
        try:
            inputs = self._inputs(name)
        except Exception as exc:
            self.notify("spflow_node_error", node=name, stage=stage, error=exc)
            raise
        assert self.workers is not None
        ctx = StageContext(name, n_jobs=n_jobs, backend=self.runner.inner_backend, verbose=self.verbose,
                           report=self.workers.report)
        self.notify("spflow_node_start", node=name, stage=stage, cached=False)
        return self.workers.submit(_execute, stage, ctx, inputs, os.getpid())

    def land(self, name: str, future: Future) -> None:
        """Check and store a finished node's output (the moment it arrives: a later failure loses nothing)."""
        stage = self.plan.stages[name]
        try:
            try:
                out, seconds, caught = future.result()
            except Exception as exc:
                raise StageError(name, stage.name, f"{type(exc).__name__}: {exc}") from exc
            if not isinstance(out, xr.Dataset):
                raise StageError(name, stage.name,
                                 f"run() must return an xarray.Dataset, returned {type(out).__name__}")
            if stage.output is not None:
                out = stage.output.annotate(out)
                stage.output.validate(out, stage=stage.name, port="output")
            out = note_units(out)
            if claims_cf(out):
                out = out.assign_attrs(Conventions=CONVENTIONS)
            meta = dict(self.plan.prov[name], node=name, pipeline=self.plan.pipeline.name, seconds=round(seconds, 6))
            self.store.save(self.plan.keys[name], out, meta, where=f"node {name!r} (stage {stage.name!r}) output")
        except Exception as exc:
            self.notify("spflow_node_error", node=name, stage=stage, error=exc)
            raise
        self.manifest.note({name: self.plan.prov[name]})
        self.memory[name] = out
        self.result.executed.append(name)
        self.notify("spflow_node_end", node=name, stage=stage, seconds=seconds, cached=False)
        _reemit(caught)  # after the output is stored: a warning turned into an error loses nothing


def _entry_problem(store: Store, key: str, stage: Stage) -> str | None:
    """Why the stored entry of a node running ``stage`` cannot be reused (None if it can).

    An integrity check, not an authenticity one (docs/architecture.md, threat model): the data file's sha256 against
    its record, the record's key and stage, and the output schema of the stage (structure only, cheap)."""
    if not store.verify(key):
        return "failed its checksum"
    try:
        record = store.record(key)
    except (OSError, ValueError) as exc:
        return f"has an unreadable record ({exc})"
    if record.get("key") != key or record.get("stage") != stage.name:
        return (f"records key {str(record.get('key'))[:12]} of stage {record.get('stage')!r}, not key {key[:12]} "
                f"of stage {stage.name!r}")
    if stage.output is not None:
        try:
            stage.output.validate(store.layout(key), stage=stage.name, port="output", values=False)
        except SchemaError as exc:
            return f"does not match the output schema of its stage ({exc})"
        except (OSError, ValueError, RuntimeError) as exc:
            return f"cannot be opened ({type(exc).__name__}: {exc})"
    return None


class _Manifest:
    """Best-effort updates of a pipeline's manifest: a failed write warns once (:class:`CacheWarning`) and the run
    goes on, since the manifest only feeds ``status``'s explanations."""

    def __init__(self, store: Store, pipeline: str):
        self.store, self.pipeline, self.warned = store, pipeline, False

    def note(self, provenances: dict[str, dict[str, Any]]) -> None:
        try:
            self.store.update_manifest(self.pipeline, provenances)
        except (OSError, CacheError) as exc:
            if not self.warned:
                self.warned = True
                warnings.warn(f"could not update the manifest of pipeline {self.pipeline!r} in cache "
                              f"{self.store.root} ({exc}); results are unaffected, but `spflow status` may not "
                              "explain why a node is stale", CacheWarning, stacklevel=3)


def _run_graph(graph: nx.DiGraph, to_run: list[str], twins: dict[str, str]) -> nx.DiGraph:
    """The dependency graph of the nodes to run, a twin's consumers waiting for the node that computes its key."""
    sub = nx.DiGraph()
    sub.add_nodes_from(to_run)
    for up, down in graph.edges:
        up = twins.get(up, up)
        if down in sub and up in sub:
            sub.add_edge(up, down)
    return sub


@dataclass
class NodeStatus:
    """Whether a node's current key is in the store, and if not, why it is stale."""

    node: str
    stage: str
    key: str
    fresh: bool
    reasons: list[str]


def status(pipeline: Pipeline, *, cache: str | Path = ".spflow") -> list[NodeStatus]:
    """For each node (in topological order): fresh (its key is cached) or stale with the causes."""
    plan = _plan(pipeline)
    store = Store(cache)
    manifest = store.manifest(pipeline.name)
    out = []
    for name in plan.order:
        key = plan.keys[name]
        problem = _entry_problem(store, key, plan.stages[name]) if store.has(key) else "is missing"
        if problem is None:
            out.append(NodeStatus(name, plan.stages[name].name, key, True, []))
            continue
        upstream = dict(pipeline.nodes[name].inputs)
        reasons = stale_reasons(manifest.get(name), plan.prov[name], upstream)
        if store.has(key):
            reasons = [f"cache entry {problem}"]
        out.append(NodeStatus(name, plan.stages[name].name, key, False, reasons))
    return out
