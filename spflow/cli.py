"""The ``spflow`` command: run, status, report, list, clean, diagnose.

    spflow run PIPELINE [--study FILE] [--profile NAME] [--quick] [--set NODE.PARAM=VALUE ...] [--until NODE]
                        [--only NODE] [--force NODE] [--jobs N] [--backend loky|threads|sequential|dask]
                        [--scheduler ADDRESS] [--cache DIR] [--out DIR]
    spflow status PIPELINE [--study FILE] [--profile NAME] [--quick] [--set NODE.PARAM=VALUE ...] [--cache DIR]
    spflow report PIPELINE [--study FILE] [--profile NAME] [--quick] [--set NODE.PARAM=VALUE ...] [--cache DIR]
                           [--out DIR]
    spflow list [pipelines|stages|effects|surrogates|commands|params]
    spflow clean [--cache DIR] [--tmp]
    spflow diagnose --observations FILE [FILE ...] [--heldout FILE ...] --base CONFIG [--catalogue NAMES]
                    [--out DIR] [--jobs N]

PIPELINE is a path to a Python file, a name in ``./pipelines/`` (``demo`` -> ``pipelines/demo.py``), the name of a
built-in or plugin pipeline (``spflow list pipelines``) or a dotted module (:mod:`spflow.core.pipeline_registry`);
the module defines ``pipeline`` (a Pipeline or a function returning one) and optionally ``report(result, outdir)``,
called after a successful run; ``report.html`` (:mod:`spflow.core.html_report`) is written next to the figures it
makes. ``--quick`` passes ``quick=True`` to ``pipeline`` when it takes it: the pipeline's small-budget profile.
``--study FILE`` passes the study (:func:`spflow.load_study`, read and validated before any work) as ``study=`` and
``--profile NAME`` as ``profile=``; a pipeline taking ``study`` runs on the bundled study without ``--study``, and the
study's summary with every default it took is printed at the start and recorded in the report.
``--set node.param=value`` overrides one node's parameter (:mod:`spflow.core.overrides`).
"""

from __future__ import annotations

import argparse
import inspect
import json
import shlex
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Any

from spflow.core.console import console_logging
from spflow.core.errors import SpflowError, StageError
from spflow.core.pipeline_registry import available_pipelines, builtin_pipeline_dir, load_pipeline_module
from spflow.core.plugins import get_commands, get_registry
from spflow.core.report_table import text_lines
from spflow.core.runners import BACKENDS

if TYPE_CHECKING:
    from spflow.core.pipeline import Pipeline

# The executor, the pipeline graph (networkx), hashing, the HTML report and the study reader are imported by the
# verbs that use them, so that `spflow list` does not load them (docs/architecture.md, "Cheap verbs stay cheap").


def _takes(obj, name: str) -> bool:
    """Whether ``obj`` is a pipeline builder (a function) taking the argument ``name``."""
    from spflow.core.pipeline import Pipeline

    return callable(obj) and not isinstance(obj, Pipeline) and name in inspect.signature(obj).parameters


def _pipeline_from(namespace: dict[str, Any], spec: str, quick: bool = False, **given: Any) -> Pipeline:
    """The module's pipeline, built with ``quick`` and the ``given`` builder arguments that are not ``None``."""
    from spflow.core.pipeline import Pipeline

    obj = namespace.get("pipeline")
    if quick and not _takes(obj, "quick"):
        raise SpflowError(f"pipeline {spec!r} has no quick profile (its pipeline() takes no 'quick' argument)")
    given = {k: v for k, v in given.items() if v is not None}
    for name in given:
        if not _takes(obj, name):
            raise SpflowError(f"pipeline {spec!r} takes no --{name} (its pipeline() has no {name!r} argument)")
    if callable(obj) and not isinstance(obj, Pipeline):
        obj = obj(**given, **({"quick": True} if quick else {}))
    if not isinstance(obj, Pipeline):
        raise SpflowError(f"pipeline module {spec!r} must define 'pipeline' (a Pipeline or a function returning one)")
    return obj


def _load(args: argparse.Namespace) -> tuple[dict[str, Any], Pipeline, list[str]]:
    """The pipeline module's namespace, its pipeline with the ``--set`` overrides applied (validated before any
    work), and the run settings (which module was used, each override), printed here and recorded in the report."""
    from spflow.core.overrides import apply_overrides

    loaded = load_pipeline_module(args.pipeline)
    study = None
    if args.study is not None or _takes(loaded.namespace.get("pipeline"), "study"):
        from spflow.study.pipeline_inputs import resolve_study, study_settings

        study = resolve_study(args.study)  # validated before any work; None -> the bundled study
    pipe = _pipeline_from(loaded.namespace, args.pipeline, args.quick, study=study,
                          profile=args.profile)
    overrides = apply_overrides(pipe, args.set or ())
    settings = [f"pipeline {args.pipeline!r}: {loaded.origin}"]
    if args.profile is not None:
        settings.append(f"--profile {args.profile}")
    if study is not None:
        settings += ([] if args.study else ["no --study: the bundled study"]) + study_settings(study)
    settings += [o.describe() for o in overrides]
    for line in settings:
        print(line)
    return loaded.namespace, pipe, settings


def _report_fingerprint(namespace: dict[str, Any], result, settings: list[str]) -> str:
    """What a report depends on: every node's key, the run settings and the pipeline modules' sources (the file, its
    siblings and the built-in pipelines, which other pipelines include)."""
    from spflow.core.hashing import canonical_hash

    module_file = namespace.get("__file__")
    directories = {builtin_pipeline_dir(), *([Path(module_file).resolve().parent] if module_file else [])}
    sources = {str(path): path.read_text() for directory in directories for path in sorted(directory.glob("*.py"))}
    return canonical_hash({"keys": dict(result.keys), "settings": settings, "sources": sources})


def _write_report(namespace: dict[str, Any], pipe: Pipeline, result, args: argparse.Namespace,
                  settings: list[str], reuse: bool = False) -> None:
    """Call the module's ``report`` (if any), print its lines and write ``report.html`` next to its figures, after a
    "Run settings" section (which pipeline module was used, the ``--set`` overrides).

    With ``reuse`` (``spflow run`` when nothing executed), a report written for the same node keys, settings and
    pipeline sources is kept and its lines reprinted instead of redrawing every figure."""
    from spflow.core.dag_svg import dag_svg
    from spflow.core.html_report import Section, provenance_rows, sections_from, write_html_report

    report = namespace.get("report")
    outdir = Path(args.out or Path("out") / pipe.name)
    outdir.mkdir(parents=True, exist_ok=True)
    fingerprint = _report_fingerprint(namespace, result, settings)
    stamp, saved, html = outdir / ".report_key", outdir / ".report_lines.json", outdir / "report.html"
    if reuse and html.is_file() and saved.is_file() and stamp.is_file() and stamp.read_text() == fingerprint:
        for line in _flat(json.loads(saved.read_text())):
            print(line)
        print(f"report (unchanged, all nodes cached): {html.resolve()}")
        return
    lines = None
    if report is not None:
        lines = report(result, outdir)
        for line in _flat(lines):
            print(line)
    states = {node: "ran" if node in result.executed else "cached" if node in result.cached else "not run"
              for node in pipe.nodes}
    dag = dag_svg(pipe.graph(), {name: node.stage for name, node in pipe.nodes.items()}, states)
    write_html_report(html, f"spflow report: {pipe.name}", [Section("Run settings", settings),
                                                             *sections_from(outdir, lines)], provenance_rows(result),
                      dag=dag)
    saved.write_text(json.dumps(_flat(lines)))
    stamp.write_text(fingerprint)
    print(f"report: {html.resolve()}")


def _flat(lines) -> list[str]:
    """A report's return value (lines, tables, or sections of them) as the text lines to print."""
    if isinstance(lines, dict):
        return [f"== {section}" if i == 0 else line for section, text in lines.items()
                for i, line in enumerate([None, *text_lines(text)])]
    return text_lines(lines or [])


def _write_failure_report(pipe: Pipeline, args: argparse.Namespace, settings: list[str], error: StageError) -> None:
    """``report.html`` of a failed run: the run settings, the failure as a warning, the DAG with the failed node,
    the nodes whose results are in the cache and those not run."""
    from spflow.core.dag_svg import dag_svg
    from spflow.core.executor import status
    from spflow.core.html_report import Section, write_html_report

    outdir = Path(args.out or Path("out") / pipe.name)
    outdir.mkdir(parents=True, exist_ok=True)
    stored = {r.node for r in status(pipe, cache=args.cache) if r.fresh}
    states = {node: "failed" if node == error.node else "cached" if node in stored else "not run"
              for node in pipe.nodes}
    lines = [f"WARNING: the run failed: {error}",
             f"{len(stored)} node(s) have their results in the cache (drawn as cached: computed before the failure, "
             "in this run or an earlier one); fix the cause and run again to continue from there"]
    html = write_html_report(outdir / "report.html", f"spflow report: {pipe.name} (failed)",
                             [Section("Run settings", settings), Section("Failure", lines)], [],
                             dag=dag_svg(pipe.graph(), {n: node.stage for n, node in pipe.nodes.items()}, states))
    (outdir / ".report_key").unlink(missing_ok=True)  # never reused as an up-to-date report
    print(f"report (failed run): {html.resolve()}", file=sys.stderr)


def _cmd_run(args: argparse.Namespace) -> int:
    from spflow.core.executor import run

    namespace, pipe, settings = _load(args)
    try:
        result = run(pipe, cache=args.cache, jobs=args.jobs, backend=args.backend, scheduler=args.scheduler,
                     until=args.until, only=args.only, force=args.force or (), verbose=True)
    except StageError as exc:
        _write_failure_report(pipe, args, settings, exc)
        raise
    print(f"{pipe.name}: {len(result.executed)} node(s) executed, {len(result.cached)} from cache")
    if not (args.until or args.only):
        _write_report(namespace, pipe, result, args, settings, reuse=not result.executed)
    return 0


def _cmd_report(args: argparse.Namespace) -> int:
    from spflow.core.executor import run, status

    namespace, pipe, settings = _load(args)
    stale = [r.node for r in status(pipe, cache=args.cache) if not r.fresh]
    if stale:
        again = ["spflow", "run", args.pipeline, *(["--quick"] if args.quick else []),
                 *(["--study", args.study] if args.study else []),
                 *(["--profile", args.profile] if args.profile else []),
                 *[word for text in args.set or () for word in ("--set", text)]]
        raise SpflowError(f"{len(stale)} node(s) of {pipe.name!r} are not in the cache ({', '.join(stale[:5])}"
                          f"{', ...' if len(stale) > 5 else ''}); run `{shlex.join(again)}` first")
    result = run(pipe, cache=args.cache)
    _write_report(namespace, pipe, result, args, settings)
    return 0


def _cmd_status(args: argparse.Namespace) -> int:
    from spflow.core.executor import status

    _, pipe, _ = _load(args)
    rows = status(pipe, cache=args.cache)
    width = max(len(r.node) for r in rows)
    for r in rows:
        state = "fresh" if r.fresh else "stale"
        why = "" if r.fresh else " — " + "; ".join(r.reasons)
        print(f"{r.node:<{width}}  {r.stage:<16} {state}{why}")
    return 0


def _cmd_list(args: argparse.Namespace) -> int:
    registry = get_registry()
    what = args.what
    if what in ("pipelines", "all"):
        print("pipelines:")
        for info in available_pipelines():
            print(f"  {info.name} ({info.origin}): {info.description}")
    if what in ("stages", "all"):
        print("stages:")
        for name in sorted(registry.stages):
            cls = registry.stages[name]
            print(f"  {name} (version {cls.version}, from {registry.providers['stage:' + name]}): {cls.description}")
            for pname, p in sorted(cls.params.items()):
                default = "required" if p.required else f"default {p.default!r}"
                print(f"      param {pname}: {p.kind.__name__}, {default}, {p.describe_range()}  {p.doc}")
            for port, schema in cls.inputs.items():
                print(f"      input {port}: {schema.describe() if schema else 'any Dataset'}")
            print(f"      output: {cls.output.describe() if cls.output else 'any Dataset'}")
    if what in ("effects", "all"):
        print("effects:")
        for name in sorted(registry.effects):
            effect = registry.effects[name]
            print(f"  {name} (default strength {effect.default_strength}): {effect.description}")
    if what in ("surrogates", "all"):
        print("surrogate kinds:")
        for kind in sorted(registry.surrogate_kinds):
            cls = registry.surrogate_kinds[kind]
            doc = (cls.__doc__ or "").strip().splitlines()[0] if cls.__doc__ else ""
            print(f"  {kind} (from {registry.providers['surrogate:' + kind]}): {doc}")
    if what in ("commands", "all"):
        print("commands from plugins:")
        for name, command in sorted(get_commands().items()):
            print(f"  {name} (from {command.provider})")
    if what in ("params", "all"):
        from spflow.plugins.forward.parameters import parameter_table

        print("forward-model parameters:")
        for row in parameter_table():
            print(f"  {row['name']:<9} [{row['unit']}] default {row['default']!r}, "
                  f"bounds [{row['lower']}, {row['upper']}]  {row['description']}")
    return 0


def _cmd_clean(args: argparse.Namespace) -> int:
    from spflow.core.cache import Store

    root = Path(args.cache)
    n = Store(root).clean(tmp_only=args.tmp)
    print(f"removed {n} {'temporary ' if args.tmp else ''}entr{'y' if n == 1 else 'ies'} from {root}")
    if not args.tmp and root.is_dir():
        kept = sorted(p.name for p in root.iterdir())
        more = ", ..." if len(kept) > 10 else ""
        print(f"kept {len(kept)} item(s) spflow does not manage: {', '.join(kept[:10])}{more}")
    return 0


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="spflow", description=__doc__.split("\n\n")[0])
    sub = parser.add_subparsers(dest="command", required=True)

    p_run = sub.add_parser("run", help="run a pipeline (cached nodes are reused)")
    p_run.add_argument("pipeline")
    p_run.add_argument("--until", action="append", metavar="NODE", help="run NODE and its ancestors only")
    p_run.add_argument("--only", action="append", metavar="NODE", help="run NODE only (inputs must be cached)")
    p_run.add_argument("--force", action="append", metavar="NODE", help="recompute NODE and its descendants")
    p_run.add_argument("--jobs", type=int, default=1, metavar="N")
    p_run.add_argument("--backend", choices=sorted(BACKENDS), default="loky")
    p_run.add_argument("--scheduler", metavar="ADDRESS", help="Dask scheduler address for --backend dask")
    p_run.add_argument("--out", metavar="DIR", help="where the pipeline's report goes (default out/<pipeline>)")

    p_status = sub.add_parser("status", help="say for each node whether it is fresh, and why it is stale")
    p_status.add_argument("pipeline")

    p_report = sub.add_parser("report", help="write the HTML report of a pipeline whose results are all cached")
    p_report.add_argument("pipeline")
    p_report.add_argument("--out", metavar="DIR", help="where the report goes (default out/<pipeline>)")
    for p in (p_run, p_status, p_report):
        p.add_argument("--quick", action="store_true", help="the pipeline's quick profile (small budgets)")
        p.add_argument("--study", metavar="FILE", help="run on this study (default: the bundled study)")
        p.add_argument("--profile", metavar="NAME", help="the pipeline's named set-up, e.g. 'thesis' (BCF1-only "
                                                         "training) for history_matching, bayesian_calibration, "
                                                         "workflow")
        p.add_argument("--set", action="append", metavar="NODE.PARAM=VALUE",
                       help="override a node's parameter (VALUE parsed as JSON, else a string); repeatable")

    p_list = sub.add_parser("list", help="list pipelines, registered stages, effects, surrogate kinds, commands and "
                                         "forward-model parameters")
    p_list.add_argument("what", nargs="?", default="all",
                        choices=["pipelines", "stages", "effects", "surrogates", "commands", "params", "all"])

    p_clean = sub.add_parser("clean", help="delete the cache (only what spflow stores; refuses a non-cache directory)")
    p_clean.add_argument("--tmp", action="store_true", help="only delete unfinished temporary entries")

    for p in (p_run, p_status, p_report, p_clean):
        p.add_argument("--cache", default=".spflow", metavar="DIR", help="cache directory (default .spflow)")
    for add_parser in dict.fromkeys(c.add_parser for c in get_commands().values()):  # the plugins' commands
        add_parser(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    core = {"run": _cmd_run, "status": _cmd_status, "report": _cmd_report, "list": _cmd_list, "clean": _cmd_clean}
    handler = core.get(args.command) or get_commands()[args.command].run
    with console_logging():
        try:
            return handler(args)
        except SpflowError as exc:
            print(f"spflow: error: {exc}", file=sys.stderr)
            return 2


if __name__ == "__main__":
    sys.exit(main())
