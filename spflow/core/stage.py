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
import sys
from collections.abc import Iterable, Iterator, Mapping
from dataclasses import dataclass
from types import MappingProxyType
from typing import Any, ClassVar, TypeVar

import xarray as xr

from .params import Param, validate_params
from .schema import DatasetSchema

__all__ = ["Stage", "StageContext"]

T = TypeVar("T")


@dataclass
class StageContext:
    """What a running stage may know about its environment.

    ``n_jobs`` is the number of workers the stage may use for its own inner parallelism (1 when the executor already
    runs several nodes side by side: one parallel layer per level). ``parallel()`` returns a configured
    :class:`joblib.Parallel`; ``progress()`` wraps an iterable and reports progress for long stages.
    """

    node: str
    n_jobs: int = 1
    backend: str = "loky"
    verbose: bool = True

    def parallel(self, **kwargs: Any):
        """A joblib ``Parallel`` with this node's worker budget and backend; inner BLAS threads capped at 1."""
        from joblib import Parallel

        if self.n_jobs == 1:
            return Parallel(n_jobs=1, **kwargs)
        if self.backend == "dask":
            return Parallel(n_jobs=-1, backend="dask", **kwargs)
        backend = "threading" if self.backend == "threading" else "loky"
        extra = {"inner_max_num_threads": 1} if backend == "loky" else {}
        from joblib import parallel_config

        with parallel_config(backend=backend, **extra):
            return Parallel(n_jobs=self.n_jobs, **kwargs)

    def progress(self, items: Iterable[T], total: int | None = None, what: str = "items") -> Iterator[T]:
        """Yield ``items`` and print ``[node] k/total`` to stderr about every 10 %."""
        if total is None and hasattr(items, "__len__"):
            total = len(items)  # type: ignore[arg-type]
        step = max(1, (total or 0) // 10)
        for k, item in enumerate(items, 1):
            yield item
            if self.verbose and total and (k % step == 0 or k == total):
                print(f"[{self.node}] {k}/{total} {what} ({100 * k // total}%)", file=sys.stderr, flush=True)


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
