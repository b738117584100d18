"""Shared test setup: ``tests/`` on sys.path (for ``oracles`` and helper modules), headless matplotlib, and a guard
that keeps ambient third-party plugins out of the suite unless a test installs one itself."""

import os
import sys
from pathlib import Path

TESTS = Path(__file__).resolve().parent
for path in (TESTS, TESTS / "core"):
    if str(path) not in sys.path:
        sys.path.insert(0, str(path))
# Worker processes (loky, dask) import test stage modules by name: give them the same path.
os.environ["PYTHONPATH"] = os.pathsep.join([str(TESTS), str(TESTS / "core"), os.environ.get("PYTHONPATH", "")])
os.environ.setdefault("MPLBACKEND", "Agg")
os.environ.setdefault("SPFLOW_DISABLE_PLUGINS", "*")
