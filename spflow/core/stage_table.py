"""The registry's table of stages: name -> Stage class, where a stage registered by reference is imported on use.

``spflow_register_stages`` plugins call ``register(StageSubclass)``, or ``register("package.module:Class",
name="stage_name")`` to declare a stage without importing its module: the CLI's cheap verbs and a run that uses a few
stages then do not import every stage module (and the numerical libraries behind them). A reference is imported the
first time the table is indexed with its name, and must name a Stage subclass whose ``name`` is the declared one.
"""

from __future__ import annotations

import importlib
from collections.abc import Iterator, Mapping

from .errors import PluginError
from .stage import Stage

__all__ = ["StageTable", "class_path", "is_reference"]


def class_path(cls: type) -> str:
    """``module:qualname`` of a class: what a reference to it says."""
    return f"{cls.__module__}:{cls.__qualname__}"


class StageTable(Mapping):
    """Stage name -> class; entries registered by reference (``"module:Class"``) are imported on first access."""

    def __init__(self) -> None:
        self._entries: dict[str, type[Stage] | str] = {}

    def add(self, name: str, entry: type[Stage] | str) -> None:
        """Set ``name`` to ``entry``: a Stage subclass or a ``"module:Class"`` reference (the registry refuses a
        name taken by another class before calling this)."""
        if name not in self._entries or isinstance(self._entries[name], str):
            self._entries[name] = entry

    def path(self, name: str) -> str:
        """``module:Class`` of the stage ``name``, without importing it."""
        entry = self._entries[name]
        return entry if isinstance(entry, str) else class_path(entry)

    def __getitem__(self, name: str) -> type[Stage]:
        entry = self._entries[name]
        if isinstance(entry, str):
            entry = self._entries[name] = _resolve(name, entry)
        return entry

    def __iter__(self) -> Iterator[str]:
        return iter(self._entries)

    def __len__(self) -> int:
        return len(self._entries)

    def __contains__(self, name: object) -> bool:
        return name in self._entries


def _resolve(name: str, reference: str) -> type[Stage]:
    module, _, qualname = reference.partition(":")
    try:
        obj = importlib.import_module(module)
        for part in qualname.split("."):
            obj = getattr(obj, part)
    except (ImportError, AttributeError) as exc:
        raise PluginError(f"stage {name!r} is registered as {reference!r}, which cannot be imported: "
                          f"{type(exc).__name__}: {exc}") from exc
    if not (isinstance(obj, type) and issubclass(obj, Stage)) or obj.name != name:
        raise PluginError(f"stage {name!r} is registered as {reference!r}, which is not a Stage subclass named "
                          f"{name!r} (got {obj!r})")
    return obj


def is_reference(entry: object) -> bool:
    """Whether ``entry`` has the form of a stage reference ``"module:Class"``."""
    return isinstance(entry, str) and entry.count(":") == 1 and all(entry.partition(":")[::2])
