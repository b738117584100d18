"""``spflow diagnose``: a gap diagnosis of any coreflood data from the command line.

    spflow diagnose --observations FILE [FILE ...] [--heldout FILE ...] --base CONFIG [--catalogue NAMES]
                    [--out DIR] [--jobs N]
    spflow diagnose --study STUDY [--base CONFIG] [--catalogue NAMES] [--out DIR] [--jobs N]

``FILE`` is a coreflood (``.nc``/``.csv`` in the format of ``docs/data.md``, or a bundled name). ``CONFIG`` is a
TOML file: the base model (``cells``, ``[effects]``, ``[fixed]``, ``[parameters]``, ``[schedules]``; see
:mod:`spflow.plugins.gap.base_model`), optionally ``catalogue = [...]`` and a ``[diagnosis]`` table with any of
the ``diagnose`` stage's options (``variables``, ``pv_step``, ``alpha``, ``shortlist``, ``max_effects``,
``max_nfev``, ``starts``, ...). ``--catalogue`` (comma-separated effect names) overrides the file's. With
``--study`` the corefloods are the study's (``calibration`` and ``heldout`` roles, each with its declared core, rate,
schedule and measurement chain) and the base model is the study's (``[parameters]``, ``[effects]``) on 60 cells; an
optional ``--base`` file then gives only ``cells``, ``catalogue`` and ``[diagnosis]``. The study's summary and every
default it took are printed first. Writes
``gap_report.nc``, ``summary.json``, the figures and ``report.html`` (run settings, the verdict, candidate scores, gap
closed and numerical-error scale as tables with units (:mod:`~spflow.plugins.gap.summary_tables`), the figures,
software versions) into ``DIR`` (default ``out/diagnose``); when the verdict leaves
two or more candidates in its ambiguity set, or an unattributed gap (the base against the candidates that close it),
also the proposed next coreflood (``next_experiment.toml``, ``.json``,
``next_experiment_study.toml``; :mod:`~spflow.plugins.gap.next_after_diagnosis`), unless ``--no-next-experiment``.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
import tomllib
from pathlib import Path

from spflow.core.errors import ParameterError
from spflow.core.html_report import Section, write_html_report
from spflow.core.params import validate_params
from spflow.core.report_table import text_lines
from spflow.core.stage import StageContext

__all__ = ["add_parser", "main"]


def add_parser(sub) -> None:
    """Add the ``diagnose`` subcommand to an argparse subparsers object."""
    p = sub.add_parser("diagnose", help="diagnose the sim-to-real gap of a base model on coreflood data")
    p.add_argument("--study", metavar="STUDY",
                   help="a study file: its corefloods and base model (docs/your_own_data.md)")
    p.add_argument("--observations", nargs="+", metavar="FILE", help="calibration corefloods (without --study)")
    p.add_argument("--heldout", nargs="+", default=[], metavar="FILE",
                   help="held-out corefloods (default: leave-one-slug-out scores)")
    p.add_argument("--base", metavar="CONFIG", help="TOML base model (and [diagnosis] options); with --study: cells, "
                                                    "catalogue and [diagnosis] only")
    p.add_argument("--catalogue", metavar="NAMES", help="comma-separated candidate effects (default: all)")
    p.add_argument("--out", default=str(Path("out") / "diagnose"), metavar="DIR")
    p.add_argument("--jobs", type=int, default=1, metavar="N", help="parallel forward runs")
    p.add_argument("--no-next-experiment", dest="next_experiment", action="store_false",
                   help="do not rank and propose the coreflood that best separates an ambiguous verdict's candidates")


def _config(path: str) -> dict:
    file = Path(path)
    if not file.is_file():
        raise ParameterError(f"--base {path!r}: no such file")
    try:
        with file.open("rb") as fh:
            return tomllib.load(fh)
    except tomllib.TOMLDecodeError as exc:
        raise ParameterError(f"--base {path!r}: not valid TOML: {exc}") from None


def _study_inputs(path: str, config: dict) -> tuple[list, list, dict, list[str]]:
    """The study's calibration and held-out sources, its base model (``cells`` from ``config``, default 60) and the
    lines of the study's summary and the defaults it took (printed here, and kept for the report)."""
    from spflow.study.pipeline_inputs import StudyInputs, study_settings

    extra = sorted(set(config) - {"cells"})
    if extra:
        raise ParameterError(f"--base with --study: the study gives the base model, so the file may hold only "
                             f"'cells', 'catalogue' and [diagnosis]; found {extra}")
    inputs = StudyInputs.of(path)
    settings = study_settings(inputs.study)
    for line in settings:
        print(line)
    base = inputs.study.base_model_config() | {"cells": config.get("cells", 60)}
    return inputs.observations(inputs.training), inputs.observations(inputs.heldout), base, settings


def main(args: argparse.Namespace) -> int:
    """Run the diagnosis of ``args`` (from :func:`add_parser`), write the report, print the verdict."""
    from .figures import write_figures
    from .next_after_diagnosis import propose_next_experiment
    from .report import report_dataset, summary
    from .stage import OPTION_PARAMS, Diagnose
    from .summary_tables import summary_items

    if args.study is None and (not args.observations or args.base is None):
        raise ParameterError("spflow diagnose needs --study STUDY, or --observations FILE ... with --base CONFIG")
    if args.study is not None and (args.observations or args.heldout):
        raise ParameterError("spflow diagnose: --study gives the corefloods; drop --observations/--heldout")
    config = _config(args.base) if args.base is not None else {}
    options = config.pop("diagnosis", {})
    validate_params("diagnose [diagnosis]", OPTION_PARAMS, options)  # names, types and ranges, before any work
    catalogue = config.pop("catalogue", [])
    if args.catalogue:
        catalogue = [name.strip() for name in args.catalogue.split(",") if name.strip()]
    if args.jobs < 1:
        raise ParameterError(f"--jobs must be >= 1, got {args.jobs}")
    settings = ["spflow diagnose: " + ", ".join(f"{k} = {v!r}" for k, v in sorted(vars(args).items())
                                              if not callable(v) and k != "command")]
    if args.study is not None:
        calibration, heldout, config, study_lines = _study_inputs(args.study, config)
        settings += study_lines
    else:
        calibration, heldout = list(args.observations), list(args.heldout)
    stage = Diagnose(calibration=calibration, heldout=heldout, base=config, catalogue=catalogue, **options)
    settings.append(stage.options.line())
    ctx = StageContext("diagnose", n_jobs=args.jobs)
    start = time.perf_counter()
    diag = stage.diagnosis(ctx)
    seconds = time.perf_counter() - start  # shown, not stored in the report: two identical runs give one report
    report = report_dataset(diag)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    report.to_netcdf(out / "gap_report.nc")
    result = summary(report)
    (out / "summary.json").write_text(json.dumps(result, indent=2))
    figures = write_figures(report, out)
    lines = summary_items(result, seconds)
    if args.next_experiment:
        proposal = propose_next_experiment(diag, out, parallel=ctx.parallel() if args.jobs > 1 else None)
        lines += proposal.lines() if proposal else ["next experiment: none proposed (no ambiguity set of two or "
                                                    "more candidates and no unattributed gap to separate)"]
    for line in text_lines(lines):
        print(line)
    html = write_html_report(out / "report.html", "spflow diagnose",
                             [Section("Run settings", settings), Section("Gap diagnosis", lines, figures)], [])
    print(f"wrote {out / 'gap_report.nc'}, {out / 'summary.json'}, {len(figures)} figures and {html}", file=sys.stderr)
    return 0
