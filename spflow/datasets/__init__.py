"""Bundled lab-like corefloods BCF1-BCF3 (thesis Table 2.5 injection sequences) as netCDF files.

``names()`` lists them, ``path(name)`` returns a file's path; :func:`spflow.io.load_coreflood` loads them by name.
The truth they were generated from (``truth/truth.toml``) is for the generation script and the tests only.
"""

from __future__ import annotations

from pathlib import Path

__all__ = ["NAMES", "names", "path", "truth_path"]

_HERE = Path(__file__).resolve().parent

#: the bundled datasets
NAMES = ("BCF1", "BCF2", "BCF3")


def names() -> list[str]:
    """Names of the bundled datasets."""
    return list(NAMES)


def path(name: str) -> Path:
    """Path of the bundled netCDF file ``name`` (case-insensitive); ``ValueError`` for an unknown name."""
    key = str(name).strip().upper()
    if key not in NAMES:
        raise ValueError(f"unknown bundled dataset {name!r}; known: {', '.join(NAMES)}")
    return _HERE / f"{key}.nc"


def truth_path() -> Path:
    """Path of the truth file (parameters, withheld mechanisms, noise, seeds). Not for pipeline code."""
    return _HERE / "truth" / "truth.toml"
