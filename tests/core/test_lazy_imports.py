"""``import spflow`` and the CLI's cheap verbs do not import numba or the numerical libraries (each check in a fresh
interpreter: what ``sys.modules`` holds afterwards). Speed itself is measured in ``benchmarks/bench_cli_startup.py``."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]

#: What an ``import spflow`` or a ``spflow list`` must not load (each costs 0.1-1 s to import).
HEAVY = ("numba", "pymoo", "GPy", "chaospy", "SALib", "arviz", "matplotlib", "emcee", "sklearn", "moocore",
         "scipy.optimize")


def loaded_after(body: str) -> dict:
    """Run ``body`` in a fresh interpreter (this worktree first on the path) and return which HEAVY modules it left
    in ``sys.modules``, plus what ``body`` stored in the variable ``result``."""
    code = (f"import io, json, sys, contextlib\nresult = None\n{body}\n"
            f"print(json.dumps({{'heavy': [m for m in {HEAVY!r} if m in sys.modules], 'result': result}}))")
    env = {**os.environ, "PYTHONPATH": str(REPO)}
    out = subprocess.run([sys.executable, "-c", code], env=env, cwd=REPO, capture_output=True, text=True, timeout=600)
    assert out.returncode == 0, out.stderr
    return json.loads(out.stdout.strip().splitlines()[-1])


def test_the_probe_sees_a_heavy_import():
    # the check below cannot pass for want of looking: importing the simulator's kernel does load numba
    assert "numba" in loaded_after("import spflow.plugins.forward.kernel")["heavy"]


def test_import_spflow_loads_no_heavy_library():
    probe = loaded_after("import spflow\nresult = [spflow.__version__, spflow.Pipeline.__name__, "
                         "spflow.ParameterError.__name__]")
    assert probe["heavy"] == []
    assert probe["result"][1:] == ["Pipeline", "ParameterError"]  # public names still resolve, on first use


@pytest.mark.parametrize("what", ["all", "stages", "surrogates", "commands", "params"])
def test_spflow_list_loads_no_heavy_library_and_lists_every_stage(what):
    body = ("from spflow.cli import main\nbuf = io.StringIO()\nwith contextlib.redirect_stdout(buf):\n"
            f"    main(['list', {what!r}])\nresult = buf.getvalue()")
    probe = loaded_after(body)
    assert probe["heavy"] == []
    if what in ("all", "stages"):  # complete: every registered stage, each with its params and ports
        from spflow.core.plugins import get_registry

        listed = {line.split()[0] for line in probe["result"].splitlines() if line.startswith("  ") and
                  not line.startswith("   ") and "(version" in line}
        assert listed == set(get_registry().stages)
    if what in ("all", "surrogates"):
        assert all(f"  {kind} (from" in probe["result"] for kind in ("pce", "gp", "pck"))


def test_a_stage_registered_by_reference_is_imported_on_use_and_checked():
    import spflow
    from spflow.core.errors import PluginError

    class References:
        @spflow.hookimpl
        def spflow_register_stages(self, register):
            register("tests_core_toy_stages_missing:Nothing", name="toy_missing")
            register("spflow.plugins.data:LoadNetCDF", name="toy_misnamed")  # the class is named 'load_netcdf'

    spflow.register_plugin(References(), "references")
    try:
        stages = spflow.get_registry().stages
        assert {"toy_missing", "toy_misnamed"} <= set(stages)  # declared, nothing imported yet
        with pytest.raises(PluginError, match="'toy_missing' is registered as 'tests_core_toy_stages_missing:Nothing'"
                                              ", which cannot be imported: ModuleNotFoundError"):
            stages["toy_missing"]
        with pytest.raises(PluginError, match="not a Stage subclass named 'toy_misnamed'"):
            stages["toy_misnamed"]
    finally:
        spflow.unregister_plugin("references")


def test_status_imports_only_the_stage_modules_its_pipeline_uses(tmp_path):
    body = ("import spflow\np = spflow.Pipeline('two')\np.add('space', 'parameter_space', params={'names': ['CRK']})\n"
            f"spflow.status(p, cache={str(tmp_path / 'cache')!r})\n"
            "result = sorted(m for m in sys.modules if m.startswith('spflow.plugins.') and m.count('.') >= 3)")
    modules = loaded_after(body)["result"]
    assert "spflow.plugins.design.parameter_space" in modules
    # (surrogate kinds are registered as classes: their modules load, light since they import no heavy library)
    assert not [m for m in modules if m.startswith(("spflow.plugins.calibration", "spflow.plugins.slug_design",
                                                    "spflow.plugins.lab", "spflow.plugins.screening",
                                                    "spflow.plugins.gap"))], modules
