"""The bundled study: BCF1-BCF3 (thesis Table 2.5 schedules) with the core and measurement chain they were made
with, BCF1 + BCF2 calibrating and BCF3 held out; the study every command uses when none is given."""

from __future__ import annotations

from pathlib import Path

from spflow import datasets

from .study import Study
from .study_file import load_study

__all__ = ["bundled_study", "bundled_study_path"]


def bundled_study_path() -> Path:
    """Path of the bundled study file (``spflow/datasets/bundled_study.toml``)."""
    return datasets.path("BCF1").parent / "bundled_study.toml"


def bundled_study() -> Study:
    """The bundled study (validated like any other)."""
    return load_study(bundled_study_path())
