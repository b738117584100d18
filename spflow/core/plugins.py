"""Plugin manager and the registries it fills.

Built-in plugins are registered exactly like third-party ones (pytest/llm style); third-party plugins are found
through the entry-point group ``spflow``.

A third-party plugin cannot take spflow down: one that fails to import (any exception, ``SystemExit`` included),
that pluggy refuses (a hook with arguments its spec lacks), or that implements a hook spflow does not define (a
misspelled name, which pluggy's ``check_pending`` would make fatal for everyone) is left out with a
:class:`~spflow.core.errors.PluginWarning` naming its entry point and distribution. Each plugin's hook calls are
isolated: its contributions are collected first and kept only if the call returns, so a raising hook contributes
nothing (and warns), and a contribution spflow refuses (a stage name already taken) is skipped with a warning while
the rest of the plugin stays. A lifecycle hook (a notification: node started, run ended...) that raises in an installed
plugin warns once per plugin and hook and the run goes on. Plugins registered in-process with :func:`register_plugin` are the caller's own code:
their errors are raised. Environment knobs:

``SPFLOW_DISABLE_PLUGINS``
    comma-separated entry-point names not to load (``*`` = no third-party plugins at all).
``SPFLOW_TRACE_PLUGINS``
    if set, print every hook call to stderr (pluggy tracing).
"""

from __future__ import annotations

import importlib.metadata
import os
import sys
import threading
import warnings
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import pluggy

from . import hashing
from .errors import PipelineError, PluginError, PluginWarning, SchemaError
from .hookspecs import PROJECT_NAME, SpflowHookSpecs
from .stage import Stage
from .class_table import StageTable, SurrogateKindTable, class_path, is_reference

__all__ = ["Registry", "Command", "get_registry", "get_commands", "reset_registry", "plugin_manager", "register_plugin",
           "unregister_plugin"]

#: The sub-commands of the CLI itself; plugins add others through ``spflow_register_commands``.
CORE_COMMANDS = ("run", "status", "report", "list", "clean")

BUILTIN_PLUGINS = ("spflow.plugins.builtin", "spflow.plugins.run_log", "spflow.plugins.progress_report")

#: Plugins registered at run time with ``register_plugin`` (e.g. from a notebook or a test), by name.
_RUNTIME_PLUGINS: dict[str, object] = {}


@dataclass
class Registry:
    """Everything the plugins contributed: stages, effects (forward model), surrogate kinds and who provided each."""

    stages: StageTable = field(default_factory=StageTable)
    effects: dict[str, Any] = field(default_factory=dict)
    surrogate_kinds: SurrogateKindTable = field(default_factory=SurrogateKindTable)
    providers: dict[str, str] = field(default_factory=dict)
    #: Calls a lifecycle hook of every plugin: ``registry.notify("spflow_node_end", node=..., ...)``.
    notify: Callable[..., None] = field(default=lambda hookname, **kwargs: None, repr=False)

    def stage(self, name: str) -> type[Stage]:
        try:
            return self.stages[name]
        except KeyError:
            known = ", ".join(sorted(self.stages)) or "none"
            raise PipelineError(f"unknown stage {name!r}; registered stages: {known}") from None

    def surrogate_kind(self, kind: str) -> type:
        """The class that rebuilds stored surrogates of ``kind``; ``SchemaError`` naming the registered kinds."""
        try:
            return self.surrogate_kinds[kind]
        except KeyError:
            raise SchemaError(f"unknown surrogate kind {kind!r}; registered kinds: {sorted(self.surrogate_kinds)} "
                              "(a plugin adds one through the hook spflow_register_surrogate_kinds)") from None


def _provider_name(obj: Any) -> str:
    module = getattr(obj, "__module__", None) or getattr(obj, "__name__", "?")
    return str(module)


def _describe(ep: importlib.metadata.EntryPoint) -> str:
    """``plugin 'name' (module, distribution name version)``: what a warning about an entry-point plugin names."""
    dist = getattr(ep, "dist", None)
    origin = f"distribution {dist.name} {dist.version}" if dist is not None else "unknown distribution"
    return f"plugin {ep.name!r} ({ep.value}, {origin})"


def _leave_out(pm: pluggy.PluginManager, name: str, label: str, what: str) -> None:
    warnings.warn(f"{label} {what}; spflow goes on without it (SPFLOW_DISABLE_PLUGINS={name} skips it)",
                  PluginWarning, stacklevel=4)
    if pm.get_plugin(name) is not None:
        pm.unregister(name=name)


def _unknown_hooks(pm: pluggy.PluginManager, name: str) -> list[str]:
    """Hooks the plugin implements that no spec defines (what ``check_pending`` refuses)."""
    plugin = pm.get_plugin(name)
    return sorted(hook.name for hook in pm.get_hookcallers(plugin) or ()
                  if not hook.has_spec() and any(impl.plugin is plugin and not impl.optionalhook
                                                 for impl in hook.get_hookimpls()))


def _load_plugins() -> tuple[pluggy.PluginManager, dict[str, str]]:
    """A plugin manager with the built-ins, the installed entry-point plugins that load cleanly (unless disabled)
    and the runtime ones; and, for the entry-point plugins, name -> the label warnings use."""
    pm = pluggy.PluginManager(PROJECT_NAME)
    pm.add_hookspecs(SpflowHookSpecs)
    for modname in BUILTIN_PLUGINS:
        module = __import__(modname, fromlist=["_"])
        pm.register(module, name=modname)
    third_party: dict[str, str] = {}
    disabled = {s.strip() for s in os.environ.get("SPFLOW_DISABLE_PLUGINS", "").split(",") if s.strip()}
    if "*" not in disabled:
        for ep in importlib.metadata.entry_points(group=PROJECT_NAME):
            if ep.name in disabled or pm.get_plugin(ep.name) is not None:
                continue
            label = _describe(ep)
            try:
                plugin = ep.load()
            except (Exception, SystemExit) as exc:  # a broken third-party plugin must not take spflow down
                _leave_out(pm, ep.name, label, f"failed to import: {type(exc).__name__}: {exc}")
                continue
            try:
                pm.register(plugin, name=ep.name)
            except Exception as exc:  # pluggy's validation of its hook implementations
                _leave_out(pm, ep.name, label, f"was refused by the plugin manager: {type(exc).__name__}: {exc}")
                continue
            unknown = _unknown_hooks(pm, ep.name)
            if unknown:
                known = ", ".join(sorted(n for n in vars(SpflowHookSpecs) if n.startswith("spflow_")))
                _leave_out(pm, ep.name, label, f"implements unknown hook(s) {', '.join(unknown)} (misspelled? "
                                               f"spflow's hooks: {known})")
                continue
            third_party[ep.name] = label
    for name, plugin in _RUNTIME_PLUGINS.items():
        pm.register(plugin, name=name)
    pm.check_pending()  # runtime plugins are the caller's own code: an unknown hook is an error
    if os.environ.get("SPFLOW_TRACE_PLUGINS"):
        pm.trace.root.setwriter(lambda msg: print(msg, end="", file=sys.stderr))
        pm.enable_tracing()
    return pm, third_party


def plugin_manager() -> pluggy.PluginManager:
    """A fresh plugin manager with the built-ins and (unless disabled) the installed entry-point plugins."""
    return _load_plugins()[0]


def _call_hook(pm: pluggy.PluginManager, third_party: dict[str, str], hookname: str,
               register: Callable[..., None]) -> None:
    """Call a ``register`` hook: the built-in and runtime plugins together (their errors propagate), then each
    third-party plugin on its own, its contributions kept only if its call returns (else a warning)."""
    others = [pm.get_plugin(name) for name in third_party]
    pm.subset_hook_caller(hookname, remove_plugins=others)(register=register)
    for name, label in third_party.items():
        plugin = pm.get_plugin(name)
        caller = pm.subset_hook_caller(hookname, remove_plugins=[p for p in pm.get_plugins() if p is not plugin])
        staged: list[tuple[tuple, dict]] = []
        try:
            caller(register=lambda *args, **kwargs: staged.append((args, kwargs)))
        except (Exception, SystemExit) as exc:
            warnings.warn(f"{label}: hook {hookname} raised {type(exc).__name__}: {exc}; none of its contributions "
                          "to that hook are used, spflow goes on with the rest", PluginWarning, stacklevel=3)
            continue
        for args, kwargs in staged:
            try:
                register(*args, **kwargs)
            except Exception as exc:  # PluginError (a name taken, not a Stage), or what register_hasher refuses
                warnings.warn(f"{label}: {hookname} contribution refused: {exc}; skipped, spflow goes on with the "
                              "rest", PluginWarning, stacklevel=3)


class _Notifier:
    """Calls a lifecycle hook: the built-in and runtime plugins together (their errors propagate: the caller's own
    code), then each installed third-party plugin on its own, a raising one reported once per plugin and hook with a
    :class:`PluginWarning` (later failures of that hook are silent) while the run goes on."""

    def __init__(self, pm: pluggy.PluginManager, third_party: dict[str, str]):
        self.pm, self.third_party = pm, third_party
        self.callers: dict[str, tuple[Any, list[tuple[str, Any]]]] = {}
        self.warned: set[tuple[str, str]] = set()
        self.lock = threading.Lock()

    def _callers(self, hookname: str) -> tuple[Any, list[tuple[str, Any]]]:
        with self.lock:
            if hookname not in self.callers:
                plugins = {name: self.pm.get_plugin(name) for name in self.third_party}
                own = self.pm.subset_hook_caller(hookname, remove_plugins=list(plugins.values()))
                each = [(name, self.pm.subset_hook_caller(
                    hookname, remove_plugins=[p for p in self.pm.get_plugins() if p is not plugin]))
                    for name, plugin in plugins.items()]
                self.callers[hookname] = (own, each)
            return self.callers[hookname]

    def __call__(self, hookname: str, **kwargs: Any) -> None:
        own, each = self._callers(hookname)
        own(**kwargs)
        for name, caller in each:
            try:
                caller(**kwargs)
            except (Exception, SystemExit) as exc:
                with self.lock:
                    first = (name, hookname) not in self.warned
                    self.warned.add((name, hookname))
                if first:
                    warnings.warn(f"{self.third_party[name]}: hook {hookname} raised {type(exc).__name__}: {exc}; "
                                  "spflow goes on (later failures of this hook are not reported)", PluginWarning,
                                  stacklevel=3)


def _build_registry(pm: pluggy.PluginManager, third_party: dict[str, str]) -> Registry:
    reg = Registry(notify=_Notifier(pm, third_party))

    def register_stage(cls: Any, name: str | None = None) -> None:
        if is_reference(cls):  # "module:Class": imported when the stage is first used (spflow.core.class_table)
            if not (isinstance(name, str) and name):
                raise PluginError(f"spflow_register_stages: a stage registered by reference ({cls!r}) needs "
                                  "name='<stage name>'")
            if name in reg.stages and reg.stages.path(name) != cls:
                raise PluginError(f"stage name {name!r} registered twice: by {reg.providers['stage:' + name]} "
                                  f"and by {cls.partition(':')[0]}")
            reg.stages.add(name, cls)
            reg.providers["stage:" + name] = cls.partition(":")[0]
            return
        if not (isinstance(cls, type) and issubclass(cls, Stage)):
            raise PluginError(f"spflow_register_stages: expected a Stage subclass or a 'module:Class' reference "
                              f"with name=..., got {cls!r}")
        if not cls.name:
            raise PluginError(f"stage class {cls.__qualname__} has no 'name'")
        if cls.name in reg.stages and reg.stages.path(cls.name) != class_path(cls):
            raise PluginError(
                f"stage name {cls.name!r} registered twice: by {reg.providers['stage:' + cls.name]} "
                f"and by {_provider_name(cls)}"
            )
        reg.stages.add(cls.name, cls)
        reg.providers["stage:" + cls.name] = _provider_name(cls)

    def register_effect(effect: Any) -> None:
        name = getattr(effect, "name", None)
        if not isinstance(name, str) or not name:
            raise PluginError(f"spflow_register_effects: expected an Effect with a name, got {effect!r}")
        if name in reg.effects and reg.effects[name] is not effect:
            raise PluginError(f"effect name {name!r} registered twice")
        reg.effects[name] = effect
        reg.providers["effect:" + name] = _provider_name(effect)

    def register_surrogate_kind(cls: Any, kind: str | None = None) -> None:
        if is_reference(cls):  # "module:Class": imported when a surrogate of the kind is first loaded
            if not (isinstance(kind, str) and kind):
                raise PluginError(f"spflow_register_surrogate_kinds: a surrogate kind registered by reference "
                                  f"({cls!r}) needs kind='<kind name>'")
            path, provider = cls, cls.partition(":")[0]
        else:
            kind = getattr(cls, "kind", None)
            if not SurrogateKindTable.accepts(cls):
                raise PluginError(f"spflow_register_surrogate_kinds: expected a Surrogate subclass or a "
                                  f"'module:Class' reference with kind=..., got {cls!r}")
            if not isinstance(kind, str) or not kind:
                raise PluginError(f"surrogate class {cls.__qualname__} must set a non-empty class attribute 'kind'")
            path, provider = class_path(cls), _provider_name(cls)
        if kind in reg.surrogate_kinds and reg.surrogate_kinds.path(kind) != path:
            raise PluginError(f"surrogate kind {kind!r} registered twice: by {reg.providers['surrogate:' + kind]} "
                              f"and by {provider}")
        reg.surrogate_kinds.add(kind, cls)
        reg.providers["surrogate:" + kind] = provider

    _call_hook(pm, third_party, "spflow_register_stages", register_stage)
    _call_hook(pm, third_party, "spflow_register_effects", register_effect)
    _call_hook(pm, third_party, "spflow_register_hashers", hashing.register_hasher)
    _call_hook(pm, third_party, "spflow_register_surrogate_kinds", register_surrogate_kind)
    return reg


_REGISTRY: Registry | None = None


def get_registry() -> Registry:
    """The process-wide registry (built on first use; ``reset_registry()`` rebuilds it)."""
    global _REGISTRY
    if _REGISTRY is None:
        _REGISTRY = _build_registry(*_load_plugins())
    return _REGISTRY


def reset_registry() -> None:
    """Forget the registry so that the next ``get_registry()`` rediscovers plugins (after installing one)."""
    global _REGISTRY, _COMMANDS
    _REGISTRY = None
    _COMMANDS = None


@dataclass(frozen=True)
class Command:
    """A sub-command a plugin added to the CLI: its parser, its runner and who provided it."""

    add_parser: Callable[..., None]
    run: Callable[..., int]
    provider: str


_COMMANDS: dict[str, Command] | None = None


def get_commands() -> dict[str, Command]:
    """The plugins' sub-commands (hook ``spflow_register_commands``), name -> :class:`Command`. Built apart from
    the registry: the CLI needs only these to build its parser, and collecting stages would import every stage
    module (seconds) before ``spflow check`` or ``spflow init`` could start."""
    global _COMMANDS
    if _COMMANDS is None:
        commands: dict[str, Command] = {}

        def register(names: Any, add_parser: Any, run: Any) -> None:
            names = (names,) if isinstance(names, str) else tuple(names)
            if not names or not all(isinstance(n, str) and n for n in names) or not (callable(add_parser)
                                                                                      and callable(run)):
                raise PluginError("spflow_register_commands: expected register(names, add_parser, run) with "
                                  f"non-empty names and two callables, got {names!r}")
            for name in names:
                if name in CORE_COMMANDS or name in commands:
                    owner = "spflow's core" if name in CORE_COMMANDS else commands[name].provider
                    raise PluginError(f"command {name!r} is already taken (by {owner}); {_provider_name(run)} "
                                      "cannot register it")
            for name in names:
                commands[name] = Command(add_parser, run, _provider_name(run))

        _call_hook(*_load_plugins(), "spflow_register_commands", register)
        _COMMANDS = commands
    return _COMMANDS


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
