"""Start-up cost of ``import spflow`` and the CLI's cheap verbs (a benchmark, not a test).

Each command runs in a fresh interpreter ``--repeat`` times; the table gives the median wall time, the number of
modules in ``sys.modules`` at exit and which heavy libraries (numba, SciPy's optimisers, pymoo, GPy, chaospy, SALib,
ArviZ, matplotlib, emcee, scikit-learn, moocore) were imported. Baselines measured in the same run: an empty
interpreter, ``import xarray``, ``import xarray`` + opening one stored result (what ``spflow status`` did per node to
check a cached entry against its stage's schema until it read the header instead: xarray's decoding of a string
variable imports dask when installed) and ``import xarray`` + reading one stored result's header
(:func:`spflow.core.netcdf_layout.read_layout`, what it does now: its floor). ``spflow status`` runs on a small pipeline
(parameter_space -> lhs_design -> forward on 10 cells -> pce) computed once into a temporary cache first (its cold run
time is printed, not part of the table). Target (issue #23): ``spflow list`` and ``spflow status`` <= 1.5 s wall on
the 2-core machine.

Run: ``python benchmarks/bench_cli_startup.py [--repeat N]`` (from the repository root; the sources found first on
``PYTHONPATH`` are the ones measured).
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import textwrap
import time
from pathlib import Path

HEAVY = ("numba", "scipy.optimize", "pymoo", "GPy", "chaospy", "SALib", "arviz", "matplotlib", "emcee", "sklearn",
         "moocore")

#: Runs the body, then prints one JSON line with what sys.modules holds (stdout of the body goes to /dev/null).
PROBE = """
import contextlib, json, os, sys
with open(os.devnull, "w") as sink, contextlib.redirect_stdout(sink):
{body}
print(json.dumps({{"modules": len(sys.modules), "heavy": [m for m in {heavy!r} if m in sys.modules]}}))
"""

PIPELINE = textwrap.dedent("""
    import spflow

    def pipeline():
        p = spflow.Pipeline("bench_cli_startup")
        p.add("space", "parameter_space", params={"names": ["AD41", "CRK"], "relative": 0.3})
        p.add("design", "lhs_design", inputs={"space": "space"}, params={"samples": 6, "seed": 1})
        p.add("runs", "forward", inputs={"design": "design"}, params={"experiments": ["BCF1"], "cells": 10})
        p.add("pce", "pce", inputs={"space": "space", "design": "design", "responses": "runs"},
              params={"degree_max": 2})
        return p
""")


def cli(*argv: str) -> str:
    return f"from spflow.cli import main\nmain({list(argv)!r})"


def measure(body: str, cwd: Path, repeat: int) -> tuple[float, int, list[str]]:
    """Median wall seconds of ``repeat`` fresh interpreters running ``body``; modules and heavy ones of the last."""
    code = PROBE.format(body=textwrap.indent(body, "    "), heavy=HEAVY)
    walls, info = [], {}
    for _ in range(repeat):
        start = time.perf_counter()
        out = subprocess.run([sys.executable, "-c", code], cwd=cwd, capture_output=True, text=True, check=False)
        walls.append(time.perf_counter() - start)
        if out.returncode != 0:
            raise SystemExit(f"failed: {body!r}\n{out.stderr}")
        info = json.loads(out.stdout.strip().splitlines()[-1])
    return statistics.median(walls), info["modules"], info["heavy"]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeat", type=int, default=5, help="fresh interpreters per command (median reported)")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory(prefix="spflow-bench-cli-") as tmp:
        work = Path(tmp)
        (work / "pipelines").mkdir()
        (work / "pipelines" / "bench_cli_startup.py").write_text(PIPELINE)
        start = time.perf_counter()
        subprocess.run([sys.executable, "-m", "spflow.cli", "run", "bench_cli_startup", "--out", str(work / "out")],
                       cwd=work, check=True, capture_output=True)
        cold = time.perf_counter() - start
        entry = next((work / ".spflow").rglob("data.nc"))
        rows = [
            ("python -c pass", "pass"),
            ("import xarray", "import xarray"),
            ("import xarray + open one stored result",
             f"import xarray\nxarray.open_dataset({str(entry)!r}, engine='netcdf4').close()"),
            ("import xarray + read one stored header",
             f"import xarray\nfrom spflow.core.netcdf_layout import read_layout\nread_layout({str(entry)!r})"),
            ("import spflow", "import spflow"),
            ("spflow --help", "from spflow.cli import build_parser\nbuild_parser().format_help()"),
            ("spflow list", cli("list")),
            ("spflow list stages", cli("list", "stages")),
            ("spflow status (4 cached nodes)", cli("status", "bench_cli_startup")),
        ]
        print(f"cold run of the 4-node pipeline (fills the cache; not in the table): {cold:.1f} s wall")
        print(f"load average at start: {' '.join(f'{x:.2f}' for x in os.getloadavg())} on {os.cpu_count()} CPUs; "
              f"median of {args.repeat} fresh interpreters\n")
        print(f"| {'command':<38} | wall s | modules | heavy modules imported |")
        print(f"|{'-' * 40}|--------|---------|{'-' * 24}|")
        for label, body in rows:
            wall, modules, heavy = measure(body, work, args.repeat)
            print(f"| {label:<38} | {wall:6.2f} | {modules:7d} | {', '.join(heavy) or 'none':<22} |")
        print(f"\nload average at end: {' '.join(f'{x:.2f}' for x in os.getloadavg())}")


if __name__ == "__main__":
    main()
