"""``spflow init`` and ``spflow check``: start a study from data files, validate a study before any simulation.

    spflow init DIR [--data FILE ...]   write DIR/study.toml (commented, valid as written) and print the defaults
                                        it chose (also marked '# DEFAULT:' in the file)
    spflow check FILE                   validate the study and print its summary and every default taken

Without ``--data``, ``init`` writes the bundled study (BCF1-BCF3) and copies its data files into DIR. A bad study
exits with status 2 and ``spflow: error: ...`` naming the file, the field and the allowed values.
"""

from __future__ import annotations

import argparse
import shutil
from pathlib import Path

from spflow import datasets

from .errors import StudyError
from .study_file import load_study
from .template import study_template

__all__ = ["add_parser", "main", "STUDY_FILE"]

#: the file ``spflow init`` writes in DIR
STUDY_FILE = "study.toml"


def add_parser(sub) -> None:
    """Add the ``init`` and ``check`` subcommands to an argparse subparsers object."""
    p_init = sub.add_parser("init", help="write a commented study template (from data files' metadata)")
    p_init.add_argument("directory", metavar="DIR", help=f"where {STUDY_FILE} goes (created if needed)")
    p_init.add_argument("--data", nargs="+", default=[], metavar="FILE",
                        help="coreflood files (CSV or netCDF); default: the bundled BCF1-BCF3")
    p_check = sub.add_parser("check", help="validate a study before any simulation; list every default taken")
    p_check.add_argument("study", metavar="FILE", help="the study file (TOML)")


def _init(args: argparse.Namespace) -> int:
    directory = Path(args.directory)
    target = directory / STUDY_FILE
    if target.exists():
        raise StudyError(f"spflow init: {str(target)!r} exists; remove it or choose another directory")
    files = [Path(f) for f in args.data]
    for f in files:
        if not f.is_file():
            raise StudyError(f"spflow init --data: no such file {str(f)!r}")
    text, defaults = study_template(directory, files)
    directory.mkdir(parents=True, exist_ok=True)
    if not files:
        for name in datasets.NAMES:
            shutil.copyfile(datasets.path(name), directory / f"{name}.nc")
    target.write_text(text, encoding="utf-8")
    print(f"wrote {target}")
    for line in defaults:
        print(f"DEFAULT {line}")
    print(f"next: edit {target} (replace every '# DEFAULT:' value you know), then `spflow check {target}`")
    return 0


def _check(args: argparse.Namespace) -> int:
    study = load_study(args.study)
    for line in study.describe():
        print(line)
    print(f"study OK: {len(study.experiments)} experiment(s), {len(study.defaults_taken)} default(s) taken")
    return 0


def main(args: argparse.Namespace) -> int:
    """Run ``init`` or ``check`` (from :func:`add_parser`); invalid input raises :class:`StudyError`."""
    try:
        return {"init": _init, "check": _check}[args.command](args)
    except StudyError:
        raise
    except ValueError as exc:  # any other validation error of a value reached through the study: still exit 2
        raise StudyError(str(exc)) from None
