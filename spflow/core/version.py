"""The installed spflow's version (what outputs record as their provenance)."""

from __future__ import annotations

from importlib.metadata import PackageNotFoundError, version

__all__ = ["__version__"]

try:
    __version__ = version("spflow")
except PackageNotFoundError:  # running from a source tree that is not installed
    __version__ = "0+unknown"
