"""The Stage contract: a named, versioned, pure function of (input Datasets, validated params) -> Dataset.

Subclass :class:`Stage`, declare ``name``, ``version``, ``inputs`` (port -> :class:`DatasetSchema`), ``output``
(a schema) and ``params`` (name -> :class:`Param`), and implement ``run(ctx, **inputs)``. Register the class through
the ``spflow_register_stages`` hook. ``run`` must not mutate its inputs and must return a new Dataset; the executor
validates inputs before and the output after, and caches it under the node's provenance key.

Example
-------
>>> class Scale(Stage):
...     name = "scale"
...     inputs = {"data": DatasetSchema(variables={"y": Variable(None)})}
...     output = DatasetSchema(variables={"y": Variable(None)})
...     params = {"factor": Param(float, 1.0, bounds=(0, None))}
...     def run(self, ctx, data):
...         return data * self.params["factor"]
"""

from __future__ import annotations

import hashlib
import inspect
import time
from collections.abc import Callable, Iterable, Iterator, Mapping
from dataclasses import dataclass, field
from math import inf
from types import MappingProxyType
from typing import Any, ClassVar, TypeVar

import xarray as xr

from .params import Param, validate_params
from .schema import DatasetSchema

__all__ = ["Stage", "StageContext"]

T = TypeVar("T")


#: Shortest interval between two progress reports of one node (the last one, ``done == total``, always goes).
PROGRESS_INTERVAL = 0.2


@dataclass
class StageContext:
    """What a running stage may know about its environment.

    ``n_jobs`` is the number of workers the stage may use for its own inner parallelism: the share of the run's
    worker budget that was free when the node started (1 when other nodes already occupy the rest). ``backend`` is
    the joblib backend of that inner parallelism (``loky``, ``threading`` or ``dask``, chosen by the runner).
    ``parallel()`` returns a configured :class:`joblib.Parallel`; ``report_progress(done, total, what)`` and
    ``progress(iterable)`` report how far a long stage has got (to the ``spflow_node_progress`` hook, through
    ``report``, which the executor sets; without it they cost nothing). ``verbose`` lets a stage print its own
    findings.
    """

    node: str
    n_jobs: int = 1
    backend: str = "loky"
    verbose: bool = True
    #: ``report(node, done, total, what)``: where progress goes (set by the executor; picklable for process runners).
    report: Callable[[str, int, int | None, str], None] | None = None
    _last_report: float = field(default=-inf, init=False, repr=False, compare=False)

    def parallel(self, **kwargs: Any):
        """A joblib ``Parallel`` with this node's worker budget and backend; inner BLAS threads capped at 1."""
        from joblib import Parallel, parallel_config

        if self.n_jobs == 1:
            return Parallel(n_jobs=1, **kwargs)
        extra = {"inner_max_num_threads": 1} if self.backend == "loky" else {}
        with parallel_config(backend=self.backend, **extra):
            return Parallel(n_jobs=self.n_jobs, **kwargs)

    def report_progress(self, done: int, total: int | None = None, what: str = "items") -> None:
        """Report that ``done`` of ``total`` units of ``what`` are done (at most every
        :data:`PROGRESS_INTERVAL` seconds; ``done == total`` always goes through)."""
        if self.report is None:
            return
        now = time.monotonic()
        if done != total and now - self._last_report < PROGRESS_INTERVAL:
            return
        self._last_report = now
        self.report(self.node, int(done), None if total is None else int(total), what)

    def progress(self, items: Iterable[T], total: int | None = None, what: str = "items") -> Iterator[T]:
        """Yield ``items``, reporting after each how many are done (``report_progress``)."""
        if total is None and hasattr(items, "__len__"):
            total = len(items)  # type: ignore[arg-type]
        self.report_progress(0, total, what)
        for k, item in enumerate(items, 1):
            yield item
            self.report_progress(k, total, what)


class Stage:
    """Base class of every pipeline stage (built-in or third-party)."""

    #: Registry name; nodes name the stage they run by this string.
    name: ClassVar[str] = ""
    #: Bump by hand whenever results change for the same params (helpers are not fingerprinted).
    version: ClassVar[str] = "1"
    #: One-line description shown by ``spflow list``.
    description: ClassVar[str] = ""
    #: Input ports -> schema (``None`` schema = any Dataset).
    inputs: ClassVar[Mapping[str, DatasetSchema | None]] = {}
    #: Optional input ports (may be left unwired).
    optional_inputs: ClassVar[frozenset[str]] = frozenset()
    #: Schema of the single output Dataset (``None`` = any Dataset).
    output: ClassVar[DatasetSchema | None] = None
    #: Parameter declarations.
    params: ClassVar[Mapping[str, Param]] = {}

    def __init__(self, **params: Any):
        if not self.name:
            raise TypeError(f"{type(self).__name__} must set a non-empty class attribute 'name'")
        self.params = MappingProxyType(validate_params(self.name, type(self).params, params))

    def run(self, ctx: StageContext, **inputs: xr.Dataset) -> xr.Dataset:  # pragma: no cover - abstract
        raise NotImplementedError(f"stage {self.name!r} does not implement run()")

    def fingerprint(self) -> str | None:
        """Extra key material for stages that read external data (e.g. a file's content hash); None otherwise."""
        return None

    @classmethod
    def code_fingerprint(cls) -> str:
        """Hash of the class source (falls back to the qualified name when the source is unavailable)."""
        try:
            source = inspect.getsource(cls)
        except (OSError, TypeError):
            source = f"{cls.__module__}.{cls.__qualname__}"
        return hashlib.sha256(source.encode()).hexdigest()[:16]

    def __repr__(self) -> str:
        args = ", ".join(f"{k}={v!r}" for k, v in self.params.items())
        return f"{type(self).__name__}({args})"
