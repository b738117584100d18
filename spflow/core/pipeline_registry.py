"""The pipelines ``spflow run NAME`` finds by name, and where each one comes from.

A pipeline module defines ``pipeline`` (a :class:`~spflow.core.pipeline.Pipeline` or a function returning one) and
optionally ``report(result, outdir)``; the first line of its docstring is its description. A pipeline is named by

1. a path to a ``.py`` file;
2. ``./pipelines/NAME.py`` in the current directory (a local file wins over a packaged pipeline of the same name);
3. a built-in pipeline, ``spflow/pipelines/NAME.py`` (shipped with the package: runnable from any directory);
4. a pipeline a third-party package contributes through the entry-point group ``spflow.pipelines``
   (``NAME = "package.module"`` in its ``pyproject.toml``); names are read from the installed metadata and a module
   is imported only when it is listed or run, so one broken plugin cannot hide the others;
5. a dotted module name.

In that order. ``SPFLOW_DISABLE_PLUGINS`` (see :mod:`spflow.core.plugins`) hides plugin pipelines as well: ``*``
hides all of them, a comma-separated list hides those entry-point names. A built-in's name cannot be taken by a
plugin (the plugin's pipeline is skipped with a warning).
"""

from __future__ import annotations

import ast
import difflib
import importlib
import importlib.metadata
import os
import runpy
import sys
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from .errors import SpflowError

__all__ = ["ENTRY_POINT_GROUP", "LOCAL_DIR", "PipelineInfo", "LoadedPipeline", "available_pipelines",
           "builtin_pipeline_dir", "load_pipeline_module"]

#: Entry-point group through which installed packages contribute pipelines (name -> module).
ENTRY_POINT_GROUP = "spflow.pipelines"
#: The directory, relative to the current one, holding the user's own pipelines by name.
LOCAL_DIR = Path("pipelines")
#: The package holding the built-in pipelines.
BUILTIN_PACKAGE = "spflow.pipelines"


@dataclass(frozen=True)
class PipelineInfo:
    """One pipeline runnable by name: where it comes from and its one-line description."""

    name: str
    origin: str
    description: str


@dataclass(frozen=True)
class LoadedPipeline:
    """A pipeline module's namespace and a sentence saying which module was used (and what it took precedence over)."""

    namespace: dict[str, Any]
    origin: str


def _warn(message: str) -> None:
    print(f"spflow: {message}", file=sys.stderr)


def builtin_pipeline_dir() -> Path:
    """The directory of the built-in pipeline modules (``spflow/pipelines``)."""
    return Path(importlib.import_module(BUILTIN_PACKAGE).__file__).resolve().parent


def _module_names(directory: Path) -> list[str]:
    if not directory.is_dir():
        return []
    return sorted(p.stem for p in directory.glob("*.py") if not p.name.startswith("_"))


def _plugin_entry_points() -> dict[str, importlib.metadata.EntryPoint]:
    """Name -> entry point of every installed plugin pipeline that is not disabled and not a built-in's name."""
    disabled = {s.strip() for s in os.environ.get("SPFLOW_DISABLE_PLUGINS", "").split(",") if s.strip()}
    if "*" in disabled:
        return {}
    builtins = set(_module_names(builtin_pipeline_dir()))
    found: dict[str, importlib.metadata.EntryPoint] = {}
    for ep in sorted(importlib.metadata.entry_points(group=ENTRY_POINT_GROUP), key=lambda e: (e.name, _dist(e))):
        if ep.name in disabled:
            continue
        if ep.name in builtins:
            _warn(f"pipeline {ep.name!r} of plugin {_dist(ep)} ignored: a built-in pipeline has that name")
            continue
        if ep.name in found:
            if found[ep.name].value != ep.value:
                _warn(f"pipeline {ep.name!r} is contributed by {_dist(found[ep.name])} and by {_dist(ep)}; "
                      f"using the first ({found[ep.name].value})")
            continue
        found[ep.name] = ep
    return found


def _dist(ep: importlib.metadata.EntryPoint) -> str:
    dist = getattr(ep, "dist", None)
    return f"{dist.name} {dist.version}" if dist is not None else "an unknown distribution"


def _first_line(doc: str | None) -> str:
    lines = (doc or "").strip().splitlines()
    return lines[0].strip() if lines else "(no description: the module has no docstring)"


def _file_description(path: Path) -> str:
    """The first docstring line of a pipeline file, read without running it."""
    try:
        return _first_line(ast.get_docstring(ast.parse(path.read_text(encoding="utf-8"), filename=str(path))))
    except (SyntaxError, UnicodeDecodeError, ValueError) as exc:
        return f"(unreadable: {type(exc).__name__}: {exc})"


def available_pipelines() -> list[PipelineInfo]:
    """Every pipeline runnable by name, sorted by name, with its origin and description.

    A local file that shadows a packaged pipeline is listed once, as the local file, saying what it shadows. A plugin
    whose module fails to import is skipped with a warning naming it."""
    builtin_dir = builtin_pipeline_dir()
    builtins = _module_names(builtin_dir)
    plugins = _plugin_entry_points()
    infos: dict[str, PipelineInfo] = {}
    for name in builtins:
        infos[name] = PipelineInfo(name, "built-in", _file_description(builtin_dir / f"{name}.py"))
    for name, ep in plugins.items():
        try:
            module = ep.load()
        except Exception as exc:  # a broken third-party pipeline must not hide the others
            _warn(f"pipeline {name!r} of plugin {_dist(ep)} failed to import ({ep.value}): {exc!r}")
            continue
        infos[name] = PipelineInfo(name, f"plugin {_dist(ep)}", _first_line(module.__doc__))
    for name in _module_names(LOCAL_DIR):
        shadowed = f"; shadows the {infos[name].origin} pipeline" if name in infos else ""
        infos[name] = PipelineInfo(name, f"local file {LOCAL_DIR / (name + '.py')}{shadowed}",
                                   _file_description(LOCAL_DIR / f"{name}.py"))
    return [infos[name] for name in sorted(infos)]


def _not_found(spec: str, plugins: Iterable[str]) -> SpflowError:
    names = sorted(set(_module_names(LOCAL_DIR)) | set(_module_names(builtin_pipeline_dir())) | set(plugins))
    close = difflib.get_close_matches(spec, names, n=3)
    hint = f" Did you mean {', '.join(close)}?" if close else ""
    return SpflowError(
        f"pipeline {spec!r} not found: not a .py file, not {LOCAL_DIR / (spec + '.py')} in {Path.cwd()}, not a "
        f"built-in or plugin pipeline, not an importable module.{hint} Available pipelines: "
        f"{', '.join(names) or 'none'} (`spflow list pipelines` describes them). To add one, write "
        f"{LOCAL_DIR / (spec + '.py')} defining pipeline() (docs/pipelines.md), pass a .py path or a dotted module, "
        f"or install a package contributing it through the entry-point group {ENTRY_POINT_GROUP!r} (docs/plugins.md)")


def _is_module_name(spec: str) -> bool:
    return all(part.isidentifier() for part in spec.split("."))


def load_pipeline_module(spec: str) -> LoadedPipeline:
    """The namespace of the pipeline module named by ``spec`` (see the module doc for the order of precedence)."""
    path = Path(spec)
    if path.suffix == ".py" and path.is_file():
        return LoadedPipeline(runpy.run_path(str(path)), f"file {path}")
    is_builtin = spec.isidentifier() and not spec.startswith("_") and (builtin_pipeline_dir() / f"{spec}.py").is_file()
    plugins = _plugin_entry_points() if not is_builtin else {}
    local = LOCAL_DIR / f"{spec}.py"
    if local.is_file():
        shadowed = ("the built-in pipeline" if is_builtin
                    else f"the pipeline of plugin {_dist(plugins[spec])}" if spec in plugins else "")
        origin = f"local file {local}" + (f" (used instead of {shadowed} of that name)" if shadowed else "")
        return LoadedPipeline(runpy.run_path(str(local)), origin)
    if is_builtin:
        module = importlib.import_module(f"{BUILTIN_PACKAGE}.{spec}")
        return LoadedPipeline(vars(module), f"built-in ({module.__name__})")
    if spec in plugins:
        ep = plugins[spec]
        try:
            module = ep.load()
        except Exception as exc:
            raise SpflowError(f"pipeline {spec!r} of plugin {_dist(ep)} failed to import ({ep.value}): "
                              f"{exc!r}") from exc
        return LoadedPipeline(vars(module), f"plugin {_dist(ep)} ({ep.value})")
    if _is_module_name(spec):
        try:
            module = importlib.import_module(spec)
        except ModuleNotFoundError as exc:
            if exc.name is None or not (spec == exc.name or spec.startswith(exc.name + ".")):
                raise SpflowError(f"pipeline module {spec!r} failed to import: {exc}") from exc
        else:
            return LoadedPipeline(vars(module), f"module {spec}")
    raise _not_found(spec, plugins)
