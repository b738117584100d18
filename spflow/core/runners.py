"""Where the nodes of a run execute: one interface, four runners (in this process, threads, processes, Dask).

The executor (:mod:`spflow.core.executor`) decides *when* a node starts -- as soon as its inputs exist and the worker
budget has room -- and hands it to a runner, which decides *where* it runs. A runner's :meth:`Runner.started` sets
up its workers for one run and yields :class:`Workers`: ``submit(fn, *args)`` returning a
:class:`concurrent.futures.Future`, and ``report``, the progress sink put in each node's
:class:`~spflow.core.stage.StageContext` (a plain callable for runners in this process, a picklable relay for the
others, whose reports reach the executor's process and the ``spflow_node_progress`` hook there).

``spflow.run(..., backend=...)`` takes a runner instance or one of the names in :data:`BACKENDS`, mapped to runner
classes here and nowhere else.
"""

from __future__ import annotations

import contextlib
import threading
import uuid
from abc import ABC, abstractmethod
from collections.abc import Callable, Iterator
from concurrent.futures import Future, ThreadPoolExecutor
from dataclasses import dataclass
from typing import Any, ClassVar

from .errors import PipelineError

__all__ = ["Runner", "Workers", "SequentialRunner", "ThreadRunner", "ProcessRunner", "DaskRunner", "BACKENDS",
           "runner_for"]

#: ``report(node, done, total, what)``
ProgressSink = Callable[[str, int, "int | None", str], None]


@dataclass
class Workers:
    """A runner's workers for one run: ``submit(fn, *args)`` -> Future, and the progress sink for the stages."""

    submit: Callable[..., Future]
    report: ProgressSink


class Runner(ABC):
    """Executes nodes submitted by the executor within the run's worker budget ``jobs``."""

    #: The name ``spflow.run(backend=...)`` and ``spflow run --backend`` know it by.
    name: ClassVar[str] = ""
    #: The joblib backend of a node's own parallelism (``StageContext.backend``, used by ``ctx.parallel()``).
    inner_backend: ClassVar[str] = "loky"

    def node_slots(self, jobs: int) -> int:
        """How many nodes may run at once with a budget of ``jobs`` workers."""
        return jobs

    @abstractmethod
    def started(self, jobs: int, report: ProgressSink) -> contextlib.AbstractContextManager[Workers]:
        """A context manager: the workers for one run, whose stages' progress goes to ``report``."""

    def __repr__(self) -> str:
        return f"{type(self).__name__}()"


def _run_now(fn: Callable[..., Any], *args: Any) -> Future:
    """Call ``fn`` here and now; its result (or exception, except ``KeyboardInterrupt``) in a finished Future."""
    future: Future = Future()
    try:
        future.set_result(fn(*args))
    except Exception as exc:
        future.set_exception(exc)
    return future


class SequentialRunner(Runner):
    """One node at a time, in this process; the whole budget goes to each node's own parallelism (loky)."""

    name = "sequential"

    def node_slots(self, jobs: int) -> int:
        return 1

    @contextlib.contextmanager
    def started(self, jobs: int, report: ProgressSink) -> Iterator[Workers]:
        yield Workers(_run_now, report)


class ThreadRunner(Runner):
    """Nodes side by side in threads of this process (stages that release the GIL: numpy, numba ``nogil``)."""

    name = "threads"
    inner_backend = "threading"

    @contextlib.contextmanager
    def started(self, jobs: int, report: ProgressSink) -> Iterator[Workers]:
        if jobs == 1:  # a pool of one thread would only add a hop
            yield Workers(_run_now, report)
            return
        pool = ThreadPoolExecutor(max_workers=jobs, thread_name_prefix="spflow-node")
        try:
            yield Workers(pool.submit, report)
        finally:
            pool.shutdown(wait=True, cancel_futures=True)


class _QueueRelay:
    """A picklable progress sink for worker processes: puts reports on a multiprocessing manager's queue."""

    def __init__(self, queue: Any):
        self.queue = queue

    def __call__(self, node: str, done: int, total: int | None, what: str) -> None:
        self.queue.put((node, done, total, what))


def _one_blas_thread(fn: Callable[..., Any], *args: Any) -> Any:
    """Worker side: ``fn(*args)`` with BLAS/OpenMP pools capped at one thread (no oversubscription of the cores)."""
    from threadpoolctl import threadpool_limits

    with threadpool_limits(1):
        return fn(*args)


class ProcessRunner(Runner):
    """Nodes side by side in loky worker processes (the default: stages holding the GIL run truly in parallel).

    Workers are reused across runs (joblib's reusable loky executor), with one BLAS/OpenMP thread each. A node given more
    than one worker parallelises inside its worker process. With a budget of one, nodes run in this process (a pool
    of one worker would only add pickling). Progress comes back through a multiprocessing manager's queue and a
    relay thread."""

    name = "loky"

    @contextlib.contextmanager
    def started(self, jobs: int, report: ProgressSink) -> Iterator[Workers]:
        if jobs == 1:
            yield Workers(_run_now, report)
            return
        import multiprocessing

        from joblib.executor import get_memmapping_executor

        # joblib's reusable executor (the one its Parallel uses: loky keeps one per process); no memmapping, so a
        # stage gets the same plain arrays in a worker as in this process
        executor = get_memmapping_executor(jobs, max_nbytes=None)
        with multiprocessing.Manager() as manager:
            queue = manager.Queue()

            def relay() -> None:
                while (item := queue.get()) is not None:
                    report(*item)

            thread = threading.Thread(target=relay, name="spflow-progress-relay", daemon=True)
            thread.start()
            try:
                yield Workers(lambda fn, *args: executor.submit(_one_blas_thread, fn, *args), _QueueRelay(queue))
            finally:
                queue.put(None)
                thread.join()


class _DaskEventRelay:
    """A picklable progress sink for Dask workers: logs the report as an event of a topic the client follows."""

    def __init__(self, topic: str):
        self.topic = topic

    def __call__(self, node: str, done: int, total: int | None, what: str) -> None:
        from distributed import get_worker

        get_worker().log_event(self.topic, (node, done, total, what))


def _settle(dask_future: Any, future: Future) -> None:
    """Copy a finished Dask future's outcome to a standard Future (called in Dask's callback thread)."""
    if dask_future.status == "finished":
        future.set_result(dask_future.result())
    else:
        future.set_exception(dask_future.exception())


class DaskRunner(Runner):
    """Nodes as tasks on a Dask distributed cluster: ``DaskRunner("tcp://host:8786")`` connects to a scheduler,
    ``DaskRunner(client=client)`` uses a connected :class:`distributed.Client`. A node's own parallelism goes to the
    cluster too (joblib's dask backend). Needs the ``dask`` extra (``pip install spflow[dask]``)."""

    name = "dask"
    inner_backend = "dask"

    def __init__(self, scheduler: str | None = None, *, client: Any = None):
        if scheduler is None and client is None:
            raise PipelineError("backend 'dask' needs a scheduler address (e.g. --scheduler tcp://127.0.0.1:8786) "
                                "or a distributed.Client")
        self.scheduler, self.client = scheduler, client

    def __repr__(self) -> str:
        return f"DaskRunner({self.scheduler or self.client!r})"

    @contextlib.contextmanager
    def started(self, jobs: int, report: ProgressSink) -> Iterator[Workers]:
        from distributed import Client

        with contextlib.ExitStack() as stack:
            client = self.client or stack.enter_context(Client(self.scheduler))
            topic = f"spflow-progress-{uuid.uuid4().hex}"
            client.subscribe_topic(topic, lambda event: report(*event[1]))
            stack.callback(client.unsubscribe_topic, topic)

            def submit(fn: Callable[..., Any], *args: Any) -> Future:
                future: Future = Future()
                client.submit(fn, *args, pure=False).add_done_callback(lambda f: _settle(f, future))
                return future

            yield Workers(submit, _DaskEventRelay(topic))


#: Names accepted by ``spflow.run(backend=...)`` and ``spflow run --backend`` -> runner class.
BACKENDS: dict[str, type[Runner]] = {"sequential": SequentialRunner, "loky": ProcessRunner,
                                     "processes": ProcessRunner, "threads": ThreadRunner,
                                     "threading": ThreadRunner, "dask": DaskRunner}


def runner_for(backend: str | Runner, scheduler: str | None = None) -> Runner:
    """The runner a ``backend`` argument names (a runner instance is returned as it is)."""
    if isinstance(backend, Runner):
        if scheduler is not None:
            raise PipelineError("give the scheduler to DaskRunner(scheduler) when passing a runner instance")
        return backend
    if backend not in BACKENDS:
        raise PipelineError(f"backend must be a Runner or one of {sorted(BACKENDS)}, got {backend!r}")
    if BACKENDS[backend] is DaskRunner:
        return DaskRunner(scheduler)
    if scheduler is not None:
        raise PipelineError(f"--scheduler is for backend 'dask', not {backend!r}")
    return BACKENDS[backend]()
