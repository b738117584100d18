"""spflow's figures leave the caller's matplotlib state alone: no backend switch, no pyplot figure left open, and no
module of the package touches pyplot or ``matplotlib.use`` (checked on the source, so a new figure module cannot
bring it back)."""

import ast
import subprocess
import sys
from pathlib import Path

import spflow

PACKAGE = Path(spflow.__file__).parent


def test_no_module_imports_pyplot_or_switches_the_backend():
    offenders = []
    for path in sorted(PACKAGE.rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Import):
                offenders += [f"{path}: import {a.name}" for a in node.names if a.name == "matplotlib.pyplot"]
            elif isinstance(node, ast.ImportFrom) and node.module in ("matplotlib", "matplotlib.pyplot"):
                offenders += [f"{path}: from {node.module} import {a.name}" for a in node.names
                              if node.module == "matplotlib.pyplot" or a.name == "pyplot"]
            elif isinstance(node, ast.Attribute) and node.attr == "use" and getattr(node.value, "id", "") == "matplotlib":
                offenders.append(f"{path}:{node.lineno}: matplotlib.use")
    assert offenders == []


SCRIPT = r"""
import sys
import matplotlib
matplotlib.use("svg")                     # the user's choice, not Agg
import matplotlib.pyplot as plt
import numpy as np
import xarray as xr
from spflow.export.opm_compare import plot_comparison

pv = np.linspace(0.0, 1.0, 11)
a = xr.Dataset({"dp": ("pv", 1e3 * (1.0 + pv))}, coords={"pv": pv})
b = xr.Dataset({"dp": ("pv", 1e3 * (1.2 + pv))}, coords={"pv": pv})
path = plot_comparison(a, b, sys.argv[1], title="two lines")
print(matplotlib.get_backend(), len(plt.get_fignums()), open(path, "rb").read(8).hex())
"""


def test_drawing_a_figure_keeps_the_callers_backend_and_leaves_no_open_figure(tmp_path):
    out = subprocess.run([sys.executable, "-c", SCRIPT, str(tmp_path / "fig.png")], capture_output=True, text=True,
                         check=True).stdout.split()
    assert out[0] == "svg"
    assert out[1] == "0"
    assert out[2] == "89504e470d0a1a0a"  # the PNG signature: the file was rendered although the backend is svg
