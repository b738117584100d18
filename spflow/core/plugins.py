"""Plugin manager and the registries it fills.

Built-in plugins are registered exactly like third-party ones (pytest/llm style); third-party plugins are found
through the entry-point group ``spflow``. Environment knobs:

``SPFLOW_DISABLE_PLUGINS``
    comma-separated entry-point names not to load (``*`` = no third-party plugins at all).
``SPFLOW_TRACE_PLUGINS``
    if set, print every hook call to stderr (pluggy tracing).
"""

from __future__ import annotations

import importlib.metadata
import os
import sys
from dataclasses import dataclass, field
from typing import Any

import pluggy

from . import hashing
from .errors import PipelineError, PluginError
from .hookspecs import PROJECT_NAME, SpflowHookSpecs
from .stage import Stage

__all__ = ["Registry", "get_registry", "reset_registry", "plugin_manager", "register_plugin", "unregister_plugin"]

BUILTIN_PLUGINS = ("spflow.plugins.builtin",)

#: Plugins registered at run time with ``register_plugin`` (e.g. from a notebook or a test), by name.
_RUNTIME_PLUGINS: dict[str, object] = {}


@dataclass
class Registry:
    """Everything the plugins contributed: stages, effects (forward model) and who provided each."""

    stages: dict[str, type[Stage]] = field(default_factory=dict)
    effects: dict[str, Any] = field(default_factory=dict)
    providers: dict[str, str] = field(default_factory=dict)

    def stage(self, name: str) -> type[Stage]:
        try:
            return self.stages[name]
        except KeyError:
            known = ", ".join(sorted(self.stages)) or "none"
            raise PipelineError(f"unknown stage {name!r}; registered stages: {known}") from None


def _provider_name(obj: Any) -> str:
    module = getattr(obj, "__module__", None) or getattr(obj, "__name__", "?")
    return str(module)


def plugin_manager() -> pluggy.PluginManager:
    """A fresh plugin manager with the built-ins and (unless disabled) the installed entry-point plugins."""
    pm = pluggy.PluginManager(PROJECT_NAME)
    pm.add_hookspecs(SpflowHookSpecs)
    for modname in BUILTIN_PLUGINS:
        module = __import__(modname, fromlist=["_"])
        pm.register(module, name=modname)
    disabled = {s.strip() for s in os.environ.get("SPFLOW_DISABLE_PLUGINS", "").split(",") if s.strip()}
    if "*" not in disabled:
        for ep in importlib.metadata.entry_points(group=PROJECT_NAME):
            if ep.name in disabled or pm.get_plugin(ep.name) is not None:
                continue
            try:
                plugin = ep.load()
            except Exception as exc:  # a broken third-party plugin must not take spflow down
                print(f"spflow: plugin {ep.name!r} failed to load: {exc!r}", file=sys.stderr)
                continue
            pm.register(plugin, name=ep.name)
    for name, plugin in _RUNTIME_PLUGINS.items():
        pm.register(plugin, name=name)
    pm.check_pending()
    if os.environ.get("SPFLOW_TRACE_PLUGINS"):
        pm.trace.root.setwriter(lambda msg: print(msg, end="", file=sys.stderr))
        pm.enable_tracing()
    return pm


def _build_registry(pm: pluggy.PluginManager) -> Registry:
    reg = Registry()

    def register_stage(cls: Any) -> None:
        if not (isinstance(cls, type) and issubclass(cls, Stage)):
            raise PluginError(f"spflow_register_stages: expected a Stage subclass, got {cls!r}")
        if not cls.name:
            raise PluginError(f"stage class {cls.__qualname__} has no 'name'")
        if cls.name in reg.stages and reg.stages[cls.name] is not cls:
            raise PluginError(
                f"stage name {cls.name!r} registered twice: by {reg.providers['stage:' + cls.name]} "
                f"and by {_provider_name(cls)}"
            )
        reg.stages[cls.name] = cls
        reg.providers["stage:" + cls.name] = _provider_name(cls)

    def register_effect(effect: Any) -> None:
        name = getattr(effect, "name", None)
        if not isinstance(name, str) or not name:
            raise PluginError(f"spflow_register_effects: expected an Effect with a name, got {effect!r}")
        if name in reg.effects and reg.effects[name] is not effect:
            raise PluginError(f"effect name {name!r} registered twice")
        reg.effects[name] = effect
        reg.providers["effect:" + name] = _provider_name(effect)

    pm.hook.spflow_register_stages(register=register_stage)
    pm.hook.spflow_register_effects(register=register_effect)
    pm.hook.spflow_register_hashers(register=hashing.register_hasher)
    return reg


_REGISTRY: Registry | None = None


def get_registry() -> Registry:
    """The process-wide registry (built on first use; ``reset_registry()`` rebuilds it)."""
    global _REGISTRY
    if _REGISTRY is None:
        _REGISTRY = _build_registry(plugin_manager())
    return _REGISTRY


def reset_registry() -> None:
    """Forget the registry so that the next ``get_registry()`` rediscovers plugins (after installing one)."""
    global _REGISTRY
    _REGISTRY = None


def register_plugin(plugin: object, name: str) -> None:
    """Register a plugin object (module or instance with ``@hookimpl`` functions) for this process."""
    if name in _RUNTIME_PLUGINS:
        raise PluginError(f"a plugin named {name!r} is already registered")
    _RUNTIME_PLUGINS[name] = plugin
    reset_registry()


def unregister_plugin(name: str) -> None:
    """Remove a plugin added with ``register_plugin``."""
    _RUNTIME_PLUGINS.pop(name, None)
    reset_registry()
