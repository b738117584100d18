"""The registry's tables of stages and surrogate kinds: name -> class, where a class registered by reference is
imported on use.

``spflow_register_stages`` plugins call ``register(StageSubclass)``, or ``register("package.module:Class",
name="stage_name")`` to declare a stage without importing its module; ``spflow_register_surrogate_kinds`` plugins
likewise ``register(SurrogateSubclass)`` or ``register("package.module:Class", kind="kind_name")``. The CLI's cheap
verbs and a run that uses a few stages then do not import every stage module and surrogate kind (and the numerical
libraries behind them). A reference is imported the first time the table is indexed with its name, and must name a
class of the table's sort whose ``name`` (a stage) or ``kind`` (a surrogate kind) is the declared one.
"""

from __future__ import annotations

import importlib
from collections.abc import Iterator, Mapping
from typing import ClassVar

from .errors import PluginError
from .stage import Stage

__all__ = ["ClassTable", "StageTable", "SurrogateKindTable", "class_path", "is_reference"]


def class_path(cls: type) -> str:
    """``module:qualname`` of a class: what a reference to it says."""
    return f"{cls.__module__}:{cls.__qualname__}"


class ClassTable(Mapping):
    """Name -> class; entries registered by reference (``"module:Class"``) are imported on first access. Subclasses
    say what the table holds (``what``, ``expected``), which class attribute carries the name (``name_attr``) and
    which classes are accepted (:meth:`accepts`)."""

    what: ClassVar[str] = "class"
    expected: ClassVar[str] = "class"
    name_attr: ClassVar[str] = "name"

    def __init__(self) -> None:
        self._entries: dict[str, type | str] = {}

    @staticmethod
    def accepts(obj: object) -> bool:
        return isinstance(obj, type)

    def add(self, name: str, entry: type | str) -> None:
        """Set ``name`` to ``entry``: a class or a ``"module:Class"`` reference (the registry refuses a name taken by
        another class before calling this)."""
        if name not in self._entries or isinstance(self._entries[name], str):
            self._entries[name] = entry

    def path(self, name: str) -> str:
        """``module:Class`` of the entry ``name``, without importing it."""
        entry = self._entries[name]
        return entry if isinstance(entry, str) else class_path(entry)

    def __getitem__(self, name: str) -> type:
        entry = self._entries[name]
        if isinstance(entry, str):
            entry = self._entries[name] = self._resolve(name, entry)
        return entry

    def __iter__(self) -> Iterator[str]:
        return iter(self._entries)

    def __len__(self) -> int:
        return len(self._entries)

    def __contains__(self, name: object) -> bool:
        return name in self._entries

    def _resolve(self, name: str, reference: str) -> type:
        module, _, qualname = reference.partition(":")
        try:
            obj = importlib.import_module(module)
            for part in qualname.split("."):
                obj = getattr(obj, part)
        except (ImportError, AttributeError) as exc:
            raise PluginError(f"{self.what} {name!r} is registered as {reference!r}, which cannot be imported: "
                              f"{type(exc).__name__}: {exc}") from exc
        if not self.accepts(obj) or getattr(obj, self.name_attr, None) != name:
            raise PluginError(f"{self.what} {name!r} is registered as {reference!r}, which is not a {self.expected} "
                              f"{'named' if self.name_attr == 'name' else 'of kind'} {name!r} (got {obj!r})")
        return obj


class StageTable(ClassTable):
    """Stage name -> Stage subclass."""

    what, expected, name_attr = "stage", "Stage subclass", "name"

    @staticmethod
    def accepts(obj: object) -> bool:
        return isinstance(obj, type) and issubclass(obj, Stage)


class SurrogateKindTable(ClassTable):
    """Surrogate kind -> the class rebuilding stored surrogates of that kind (anything with ``from_dataset``: the
    Surrogate base class lives in a plugin package, which the core does not import)."""

    what, expected, name_attr = "surrogate kind", "surrogate class (with from_dataset)", "kind"

    @staticmethod
    def accepts(obj: object) -> bool:
        return isinstance(obj, type) and callable(getattr(obj, "from_dataset", None))


def is_reference(entry: object) -> bool:
    """Whether ``entry`` has the form of a class reference ``"module:Class"``."""
    return isinstance(entry, str) and entry.count(":") == 1 and all(entry.partition(":")[::2])
