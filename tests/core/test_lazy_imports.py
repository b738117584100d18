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
#: What ``spflow list`` does not need either (it imports xarray, through the stages' schemas, and nothing heavier):
#: SciPy (Kriging's linear algebra, the slug design's constants), joblib (the slug design's parallel map),
#: networkx (the pipeline graph), dask and the executor. (It imports the surrogate kinds' classes, for their
#: descriptions: light, since they import SciPy when a model is fitted.)
NOT_FOR_LIST = ("scipy", "joblib", "networkx", "dask", "spflow.core.executor")
#: What ``spflow status`` on a pipeline without Kriging does not need: the Kriging modules (surrogate kinds are
#: registered by reference), SciPy's linear algebra they import, joblib, the stages its pipeline does not use, and
#: dask (which xarray imports, when installed, to open a file holding strings: the schema check of a cached entry
#: reads the netCDF header instead, spflow.core.netcdf_layout).
NOT_FOR_STATUS = ("dask", "joblib", "scipy.linalg", "spflow.plugins.surrogates.gp_model",
                  "spflow.plugins.surrogates.pck_model", "spflow.plugins.surrogates.kriging",
                  "spflow.plugins.slug_design.stage")


def loaded_after(body: str, look_for: tuple[str, ...] = HEAVY, cwd: Path = REPO) -> dict:
    """Run ``body`` in a fresh interpreter (this worktree first on the path, in ``cwd``) and return which of the
    modules ``look_for`` it left in ``sys.modules`` (as ``heavy``), plus what ``body`` stored in ``result``."""
    code = (f"import io, json, sys, contextlib\nresult = None\n{body}\n"
            f"print(json.dumps({{'heavy': [m for m in {look_for!r} if m in sys.modules], 'result': result}}))")
    env = {**os.environ, "PYTHONPATH": str(REPO)}
    out = subprocess.run([sys.executable, "-c", code], env=env, cwd=cwd, capture_output=True, text=True, timeout=600)
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
    probe = loaded_after(body, HEAVY + NOT_FOR_LIST)
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


def test_cli_status_of_a_cached_pipeline_loads_only_what_its_stages_need(tmp_path):
    import spflow

    (tmp_path / "pipelines").mkdir()
    (tmp_path / "pipelines" / "two.py").write_text(
        "import spflow\n\ndef pipeline():\n    p = spflow.Pipeline('two')\n"
        "    p.add('space', 'parameter_space', params={'names': ['CRK', 'AD41']})\n"
        "    p.add('design', 'lhs_design', inputs={'space': 'space'}, params={'samples': 4})\n    return p\n")
    namespace = {}
    exec((tmp_path / "pipelines" / "two.py").read_text(), namespace)
    spflow.run(namespace["pipeline"](), cache=tmp_path / ".spflow", verbose=False)
    body = ("from spflow.cli import main\nbuf = io.StringIO()\nwith contextlib.redirect_stdout(buf):\n"
            "    main(['status', 'two'])\nresult = buf.getvalue()")
    probe = loaded_after(body, HEAVY + NOT_FOR_STATUS, cwd=tmp_path)
    assert probe["heavy"] == []
    assert [line.split()[-1] for line in probe["result"].splitlines()[1:]] == ["fresh", "fresh"]  # both cached


def test_a_surrogate_kind_registered_by_reference_is_imported_on_use_and_checked():
    import spflow
    from spflow.core.errors import PluginError

    class References:
        @spflow.hookimpl
        def spflow_register_surrogate_kinds(self, register):
            register("tests_core_surrogate_missing:Nothing", kind="toy_missing")
            register("spflow.plugins.surrogates.gp_model:GP", kind="toy_miskinded")  # GP.kind is 'gp'

    spflow.register_plugin(References(), "kind_references")
    try:
        kinds = spflow.get_registry().surrogate_kinds
        assert {"toy_missing", "toy_miskinded", "pce", "gp", "pck"} <= set(kinds)  # declared, nothing imported yet
        with pytest.raises(PluginError, match="surrogate kind 'toy_missing' is registered as "
                                              "'tests_core_surrogate_missing:Nothing', which cannot be imported"):
            kinds["toy_missing"]
        with pytest.raises(PluginError, match="not a surrogate class \\(with from_dataset\\) of kind 'toy_miskinded'"):
            kinds["toy_miskinded"]
        assert kinds["gp"].kind == "gp"  # a built-in reference resolves to its class
    finally:
        spflow.unregister_plugin("kind_references")

    class NoKind:
        @spflow.hookimpl
        def spflow_register_surrogate_kinds(self, register):
            register("spflow.plugins.surrogates.gp_model:GP")

    spflow.register_plugin(NoKind(), "kind_without_name")
    try:
        with pytest.raises(PluginError, match="registered by reference .* needs kind="):
            spflow.get_registry()
    finally:
        spflow.unregister_plugin("kind_without_name")
