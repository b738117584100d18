"""Run a pipeline: plan from provenance keys, reuse cached results, execute the rest level by level in parallel.

* Keys are computed for every node before anything runs (see :mod:`spflow.core.provenance`).
* A node whose key is in the store is not executed if the entry passes its checksum, records that key and stage, and
  matches the stage's output schema (dims, variables, dtypes, units: read without loading the arrays); any other
  entry is discarded with a :class:`~spflow.core.errors.CacheIntegrityWarning` and recomputed.
* Runs sharing a cache coordinate through per-key locks: a node is computed under its key's lock, and a run that
  finds the lock taken computes its other ready nodes first, then waits and reuses what the other run stored. A run
  never waits for a lock while holding another, so two runs cannot deadlock.
* Nodes to execute run by topological generation. A generation of several nodes runs them side by side with joblib
  (each node then gets ``n_jobs=1`` for its own work); a lone node gets the whole worker budget for its inner
  parallelism. One parallel layer per level.
* Nodes with the same key (the same stage, params and upstream data, e.g. one node copied into two included
  sub-pipelines) are computed once per run; the others read the stored result.
* Each finished node is validated and written to the store as soon as it completes, so an exception or
  KeyboardInterrupt loses nothing that finished; the next run resumes from there. A failed write (full or read-only
  disk) stops the run with a :class:`~spflow.core.errors.CacheError` naming the node, the cache and the cause.
* The per-pipeline manifest (behind ``status``'s explanations) is written only when it changes, and best-effort: a
  failure is a :class:`~spflow.core.errors.CacheWarning`. A fully cached run writes nothing, so it works on a
  read-only cache.
"""

from __future__ import annotations

import contextlib
import sys
import time
import warnings
from collections.abc import Iterable, Iterator, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import networkx as nx
import xarray as xr

from .cache import Store
from .errors import CacheError, CacheIntegrityWarning, CacheWarning, PipelineError, SchemaError, StageError
from .pipeline import Pipeline
from .plugins import get_registry
from .provenance import key_of, provenance, stale_reasons
from .stage import Stage, StageContext

__all__ = ["run", "status", "RunResult", "NodeStatus", "BACKENDS"]

#: CLI/backend names -> joblib backend names.
BACKENDS = {"loky": "loky", "threads": "threading", "threading": "threading", "dask": "dask"}


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


def _execute(stage: Stage, ctx: StageContext, inputs: dict[str, xr.Dataset]) -> tuple[xr.Dataset, float]:
    """Run one stage (in whatever process joblib chose) and return its output and wall time."""
    t0 = time.perf_counter()
    out = stage.run(ctx, **inputs)
    return out, time.perf_counter() - t0


@contextlib.contextmanager
def _backend_context(backend: str, scheduler: str | None) -> Iterator[None]:
    if backend != "dask":
        yield
        return
    if not scheduler:
        raise PipelineError("backend 'dask' needs a scheduler address (e.g. --scheduler tcp://127.0.0.1:8786)")
    from distributed import Client
    from joblib import parallel_config

    with Client(scheduler), parallel_config(backend="dask"):
        yield


def run(pipeline: Pipeline, *, cache: str | Path = ".spflow", jobs: int = 1, backend: str = "loky",
        scheduler: str | None = None, until: Iterable[str] | str | None = None,
        only: Iterable[str] | str | None = None, force: Iterable[str] | str = (), verbose: bool = False) -> RunResult:
    """Run ``pipeline`` and return its results (a mapping node -> Dataset).

    Parameters
    ----------
    cache: directory of the result store.
    jobs: worker budget (nodes side by side, or a lone node's inner parallelism).
    backend: ``loky`` (processes, default), ``threads`` or ``dask`` (with ``scheduler`` = address).
    until: run only these nodes and their ancestors.
    only: run only these nodes; their inputs must already be in the cache.
    force: recompute these nodes and everything downstream of them even if cached.
    """
    if backend not in BACKENDS:
        raise PipelineError(f"backend must be one of {sorted(BACKENDS)}, got {backend!r}")
    if isinstance(jobs, bool) or not isinstance(jobs, int) or jobs < 1:
        raise PipelineError(f"jobs must be an integer >= 1 (not a bool), got {jobs!r}")
    plan = _plan(pipeline)
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

    memory: dict[str, xr.Dataset] = {}

    def inputs_of(name: str) -> dict[str, xr.Dataset]:
        out = {}
        for port, up in pipeline.nodes[name].inputs.items():
            if up not in memory:
                memory[up] = store.load(plan.keys[up])
            out[port] = memory[up]
        return out

    def finish(name: str, out: Any, seconds: float) -> None:
        stage = plan.stages[name]
        if not isinstance(out, xr.Dataset):
            raise StageError(name, stage.name, f"run() must return an xarray.Dataset, returned {type(out).__name__}")
        if stage.output is not None:
            stage.output.validate(out, stage=stage.name, port="output")
        meta = dict(plan.prov[name], node=name, pipeline=pipeline.name, seconds=round(seconds, 6))
        store.save(plan.keys[name], out, meta, where=f"node {name!r} (stage {stage.name!r}) output")
        manifest.note({name: plan.prov[name]})
        memory[name] = out
        result.executed.append(name)
        if verbose:
            print(f"[spflow] ({len(result.executed)}/{len(to_run)}) {name}: ran {stage.name} in {seconds:.2f} s",
                  file=sys.stderr)

    def prepare(name: str) -> dict[str, xr.Dataset]:
        stage = plan.stages[name]
        inputs = inputs_of(name)
        for port, ds in inputs.items():
            schema = stage.inputs.get(port)
            if schema is not None:
                schema.validate(ds, stage=stage.name, port=port)
        return inputs

    sub = _run_graph(plan.graph, to_run, twins)
    if verbose and to_run:
        print(f"[spflow] {pipeline.name}: {len(to_run)} node(s) to run, {len(result.cached)} cached", file=sys.stderr)

    def still_needed(name: str) -> bool:
        """With the node's lock held: False if another run stored a good entry meanwhile (then it is reused);
        otherwise clear any entry in the way (forced, or failing the checks) and return True."""
        key = plan.keys[name]
        try:
            if store.has(key):
                if name not in forced and _entry_problem(store, key, plan.stages[name]) is None:
                    result.cached.append(name)
                    manifest.note({name: plan.prov[name]})
                    if verbose:
                        print(f"[spflow] {name}: computed meanwhile by another run; reused", file=sys.stderr)
                    return False
                store.discard(key)
        except OSError as exc:
            raise CacheError(f"node {name!r}: cannot replace its cache entry in {store.root}: {exc}") from exc
        return True

    jb_backend = BACKENDS[backend]
    with _backend_context(backend, scheduler):
        for generation in nx.topological_generations(sub):
            pending = sorted(generation)
            while pending:
                mine = _claim(store, pending, plan.keys)
                pending = [n for n in pending if n not in mine]
                try:
                    runnable = [n for n in mine if still_needed(n)]
                    if jobs > 1 and len(runnable) > 1:
                        _run_parallel(runnable, plan, prepare, finish, jobs, jb_backend, verbose)
                    else:
                        for name in runnable:
                            _run_serial(name, plan, prepare, finish, jobs, jb_backend, verbose)
                finally:
                    for name in mine:
                        store.release(plan.keys[name])
    computed_twins = [n for n in twins if twins[n] in result.executed]
    result.cached += computed_twins
    manifest.note({name: plan.prov[name] for name in computed_twins})
    return result


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
            with store.opened(key) as ds:
                stage.output.validate(ds, stage=stage.name, port="output", values=False)
        except SchemaError as exc:
            return f"does not match the output schema of its stage ({exc})"
        except (OSError, ValueError, RuntimeError) as exc:
            return f"cannot be opened ({type(exc).__name__}: {exc})"
    return None


def _claim(store: Store, pending: list[str], keys: dict[str, str]) -> list[str]:
    """Lock the keys of as many pending nodes as are free, without waiting; if none is free, wait for the first one
    (holding no other lock while waiting, so concurrent runs cannot deadlock)."""
    def acquire(name: str, blocking: bool) -> bool:
        try:
            return store.acquire(keys[name], blocking=blocking,
                                 waiting=f"{name}: another run is computing this node")
        except OSError as exc:
            raise CacheError(f"node {name!r}: cannot lock its cache entry in {store.root}: {exc}") from exc

    mine: list[str] = []
    try:
        for name in pending:
            if acquire(name, blocking=False):
                mine.append(name)
        if not mine:
            acquire(pending[0], blocking=True)
            mine.append(pending[0])
    except BaseException:  # e.g. KeyboardInterrupt while waiting: hand back what was taken
        for name in mine:
            store.release(keys[name])
        raise
    return mine


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


def _run_serial(name, plan, prepare, finish, jobs, jb_backend, verbose) -> None:
    ctx = StageContext(name, n_jobs=jobs, backend=jb_backend, verbose=verbose)
    inputs = prepare(name)
    if verbose:
        print(f"[spflow] {name}: running {plan.stages[name].name} ...", file=sys.stderr)
    try:
        out, seconds = _execute(plan.stages[name], ctx, inputs)
    except Exception as exc:
        raise StageError(name, plan.stages[name].name, f"{type(exc).__name__}: {exc}") from exc
    finish(name, out, seconds)


def _run_graph(graph: nx.DiGraph, to_run: list[str], twins: dict[str, str]) -> nx.DiGraph:
    """The dependency graph of the nodes to run, a twin's consumers waiting for the node that computes its key."""
    sub = nx.DiGraph()
    sub.add_nodes_from(to_run)
    for up, down in graph.edges:
        up = twins.get(up, up)
        if down in sub and up in sub:
            sub.add_edge(up, down)
    return sub


def _run_parallel(generation, plan, prepare, finish, jobs, jb_backend, verbose) -> None:
    from joblib import Parallel, delayed, parallel_config

    n_jobs = -1 if jb_backend == "dask" else min(jobs, len(generation))
    tasks = []
    for name in generation:
        ctx = StageContext(name, n_jobs=1, backend=jb_backend, verbose=verbose)
        tasks.append(delayed(_tagged_execute)(name, plan.stages[name], ctx, prepare(name)))
    extra = {"inner_max_num_threads": 1} if jb_backend == "loky" else {}
    with parallel_config(backend=jb_backend, **extra):
        outputs = Parallel(n_jobs=n_jobs, return_as="generator_unordered")(tasks)
        failures: list[tuple[str, Exception]] = []
        for name, out, seconds, error in outputs:
            if error is None:
                try:
                    finish(name, out, seconds)
                except Exception as exc:  # invalid output or failed write: the siblings are still stored
                    failures.append((name, exc))
            else:
                exc, message = error
                failure = StageError(name, plan.stages[name].name, message)
                failure.__cause__ = exc
                failures.append((name, failure))
    if failures:  # raised once every sibling has finished and been stored
        raise min(failures, key=lambda item: item[0])[1]


def _tagged_execute(name: str, stage: Stage, ctx: StageContext, inputs: dict[str, xr.Dataset]):
    """Worker-side wrapper: return errors as values so that finished siblings are still stored."""
    try:
        out, seconds = _execute(stage, ctx, inputs)
        return name, out, seconds, None
    except Exception as exc:
        return name, None, 0.0, (exc, f"{type(exc).__name__}: {exc}")


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
