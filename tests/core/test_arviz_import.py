"""ArviZ is imported only where a computation needs it, and no ArviZ FutureWarning reaches a user.

ArviZ 0.2x warns about its 1.0 refactor on import, once a day per user (a stamp file under the user cache dir), so
each check runs in a fresh interpreter with an empty ``XDG_CACHE_HOME``: there the warning is certain to be raised by
a bare ``import arviz`` (checked first, so the other checks cannot pass for want of a warning to catch).
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]

# Prints the FutureWarnings raised while running BODY (one per line, "module: message") and whether arviz was imported.
PROBE = """
import sys, warnings
warnings.simplefilter("always")
with warnings.catch_warnings(record=True) as caught:
    warnings.simplefilter("always")
{body}
for w in caught:
    if issubclass(w.category, FutureWarning):
        print("FUTUREWARNING", w.filename, str(w.message).strip().splitlines()[0])
print("ARVIZ_IMPORTED", "arviz" in sys.modules)
"""


def run_probe(body: str, tmp_path: Path) -> tuple[list[str], bool]:
    cache = tmp_path / "cache"
    cache.mkdir()
    env = {**os.environ, "XDG_CACHE_HOME": str(cache), "PYTHONPATH": str(REPO)}
    code = PROBE.format(body="\n".join("    " + line for line in body.strip().splitlines()))
    out = subprocess.run([sys.executable, "-c", code], env=env, cwd=REPO, capture_output=True, text=True,
                         timeout=600)
    assert out.returncode == 0, out.stderr
    lines = out.stdout.splitlines()
    warned = [line for line in lines if line.startswith("FUTUREWARNING")]
    imported = [line for line in lines if line.startswith("ARVIZ_IMPORTED")]
    return warned, imported[-1].endswith("True")


@pytest.fixture(scope="module")
def bare_import_warns(tmp_path_factory):
    warned, _ = run_probe("import arviz", tmp_path_factory.mktemp("bare"))
    return warned


def test_bare_arviz_import_warns_in_a_fresh_cache(bare_import_warns):
    # the premise of the checks below: without spflow's care, ArviZ's import does raise its FutureWarning
    assert any("ArviZ is undergoing a major refactor" in line for line in bare_import_warns), bare_import_warns


def test_plugin_loading_does_not_import_arviz(bare_import_warns, tmp_path):
    # what every run does: load the built-in plugins, including the gap diagnosis (which uses PSIS-LOO)
    warned, imported = run_probe("import spflow.plugins.gap.diagnosis\nimport spflow.plugins.calibration.diagnostics",
                                 tmp_path)
    assert not imported
    assert warned == []


def test_psis_loo_and_mcmc_summary_raise_no_future_warning(bare_import_warns, tmp_path):
    # the two computations that import ArviZ: PSIS-LOO of a fitted model and the MCMC summary (R-hat, ESS)
    body = """
import numpy as np, xarray as xr
from spflow.plugins.calibration.diagnostics import summary
from spflow.plugins.gap.least_squares import Fit
from spflow.plugins.gap.psis_loo import psis_loo
rng = np.random.default_rng(0)
psis_loo(Fit(np.full(2, 0.5), (), 2, rng.normal(size=30), rng.normal(size=(30, 2)), 0, ""), draws=200)
theta = rng.normal(size=(2, 300, 2))
summary(xr.Dataset({"theta": (("chain", "draw", "param"), theta)}, coords={"param": ["a", "b"]}))
"""
    warned, imported = run_probe(body, tmp_path)
    assert imported
    assert warned == []
