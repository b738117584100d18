"""A broken third-party plugin cannot take spflow down: each failure is a PluginWarning naming the plugin (entry point,
module, distribution) and spflow goes on with the built-ins and the healthy plugins.

Plugins are installed the way pip leaves them: a ``<dist>-<version>.dist-info`` directory with ``entry_points.txt``
next to the module, on ``sys.path``."""

import os
import subprocess
import sys
import textwrap
import uuid

import pytest
import xarray as xr

import spflow
from spflow.core.plugins import get_registry, reset_registry

HEALTHY = '''
import numpy as np, xarray as xr, spflow

class Healthy(spflow.Stage):
    name = "{stage}"
    output = spflow.DatasetSchema(variables={{"y": spflow.Variable(("x",), units="m")}})

    def run(self, ctx):
        return xr.Dataset({{"y": ("x", np.arange(3.0), {{"units": "m"}})}})

@spflow.hookimpl
def spflow_register_stages(register):
    register(Healthy)
'''

BROKEN = {
    "import_error": "raise ImportError('needs libfoo.so')\n",
    "system_exit": "import sys\nsys.exit(3)\n",
    "raising_hook": HEALTHY + '''
@spflow.hookimpl
def spflow_register_effects(register):
    raise RuntimeError("effect table missing")
''',
    "partial_then_raise": '''
import spflow

class Half(spflow.Stage):
    name = "half_registered"

@spflow.hookimpl
def spflow_register_stages(register):
    register(Half)
    raise ValueError("second stage broken")
''',
    "exits_in_hook": '''
import sys, spflow

@spflow.hookimpl
def spflow_register_stages(register):
    sys.exit("no licence")
''',
    "misspelled": HEALTHY + '''
@spflow.hookimpl
def spflow_register_stage(register):  # missing "s"
    pass
''',
    "bad_signature": '''
import spflow

@spflow.hookimpl
def spflow_register_stages(register, context):  # the spec has no 'context'
    pass
''',
    "takes_a_builtin_name": '''
import spflow

class Impostor(spflow.Stage):
    name = "load_netcdf"

@spflow.hookimpl
def spflow_register_stages(register):
    register(Impostor)
''',
}

MESSAGES = {
    "import_error": "failed to import: ImportError: needs libfoo.so",
    "system_exit": "failed to import: SystemExit: 3",
    "raising_hook": "hook spflow_register_effects raised RuntimeError: effect table missing; none of its contributions",
    "partial_then_raise": "hook spflow_register_stages raised ValueError: second stage broken",
    "exits_in_hook": "hook spflow_register_stages raised SystemExit: no licence",
    "misspelled": "implements unknown hook(s) spflow_register_stage (misspelled?",
    "bad_signature": "was refused by the plugin manager: PluginValidationError",
    "takes_a_builtin_name": "spflow_register_stages contribution refused: stage name 'load_netcdf' registered twice",
}


@pytest.fixture
def site(tmp_path, monkeypatch):
    """``install(kind)`` writes a distribution ``spflow-<kind>`` 1.2 whose entry point ``<kind>`` is a fresh module;
    returns (entry-point name, module name)."""
    root = tmp_path / "site"
    root.mkdir()
    monkeypatch.syspath_prepend(str(root))
    monkeypatch.setenv("SPFLOW_DISABLE_PLUGINS", "")
    modules = []

    def install(kind: str, source: str) -> str:
        module = f"plug_{kind}_{uuid.uuid4().hex[:8]}"
        modules.append(module)
        (root / f"{module}.py").write_text(source)
        info = root / f"spflow_{kind}-1.2.dist-info"
        info.mkdir()
        (info / "METADATA").write_text(f"Metadata-Version: 2.1\nName: spflow-{kind}\nVersion: 1.2\n")
        (info / "entry_points.txt").write_text(f"[spflow]\n{kind} = {module}\n")
        return module

    reset_registry()
    yield install
    for module in modules:
        sys.modules.pop(module, None)
    reset_registry()


@pytest.mark.parametrize("kind", sorted(BROKEN))
def test_a_broken_plugin_warns_with_its_name_and_the_rest_goes_on(site, kind, tmp_path):
    module = site(kind, BROKEN[kind].format(stage=f"{kind}_ramp"))
    healthy = site("healthy", HEALTHY.format(stage="healthy_ramp"))
    with pytest.warns(spflow.PluginWarning) as caught:
        registry = get_registry()
    messages = [str(w.message) for w in caught]
    assert len(messages) == 1, messages
    assert messages[0].startswith(f"plugin {kind!r} ({module}, distribution spflow-{kind} 1.2)")
    assert MESSAGES[kind] in messages[0]
    assert {"load_netcdf", "forward", "healthy_ramp"} <= set(registry.stages)  # built-ins and the healthy plugin
    assert registry.providers["stage:healthy_ramp"] == healthy
    assert registry.providers["stage:load_netcdf"].startswith("spflow.")  # the impostor did not replace it
    assert "half_registered" not in registry.stages  # a hook that raised contributes nothing
    result = spflow.run(spflow.Pipeline("after").add("r", "healthy_ramp"), cache=tmp_path / "cache")
    assert result["r"]["y"].values.tolist() == [0.0, 1.0, 2.0]


def test_a_raising_hook_keeps_the_plugins_other_hooks(site):
    site("raising_hook", BROKEN["raising_hook"].format(stage="still_here"))
    with pytest.warns(spflow.PluginWarning, match="plugin 'raising_hook'"):
        registry = get_registry()
    assert "still_here" in registry.stages  # its stage hook worked; only the effects hook failed


def test_a_plugin_exiting_at_import_does_not_stop_the_command(site):
    """The issue's case: ``SystemExit`` at import used to end every command with exit 3 and no message."""
    site("system_exit", BROKEN["system_exit"])
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(sys.path), SPFLOW_DISABLE_PLUGINS="")
    ran = subprocess.run([sys.executable, "-m", "spflow.cli", "list", "stages"], capture_output=True, text=True,
                         env=env, timeout=300)
    assert ran.returncode == 0, ran.stderr
    assert "load_netcdf" in ran.stdout
    assert "PluginWarning: plugin 'system_exit' (plug_system_exit_" in ran.stderr
    assert "failed to import: SystemExit: 3; spflow goes on without it" in ran.stderr
    assert "Traceback" not in ran.stderr


def test_disabling_the_broken_plugin_silences_it(site, monkeypatch, recwarn):
    site("system_exit", BROKEN["system_exit"])
    monkeypatch.setenv("SPFLOW_DISABLE_PLUGINS", "system_exit")
    assert "load_netcdf" in get_registry().stages
    assert not [w for w in recwarn if issubclass(w.category, spflow.PluginWarning)]


def test_runtime_plugins_are_the_callers_code_and_still_raise():
    class Raising:
        @spflow.hookimpl
        def spflow_register_stages(self, register):
            raise RuntimeError("my own bug")

    spflow.register_plugin(Raising(), name="raising")
    try:
        with pytest.raises(RuntimeError, match="my own bug"):
            get_registry()
    finally:
        spflow.unregister_plugin("raising")


PIPELINE_EXITS = textwrap.dedent('''
    """A plugin pipeline whose module exits."""
    import sys
    sys.exit(4)
    ''')


def test_a_plugin_pipeline_exiting_at_import_is_a_warning(site, tmp_path):
    from spflow.core.pipeline_registry import available_pipelines

    root = tmp_path / "site"
    (root / "exiting_pipeline.py").write_text(PIPELINE_EXITS)
    info = root / "spflow_pipes-0.1.dist-info"
    info.mkdir()
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: spflow-pipes\nVersion: 0.1\n")
    (info / "entry_points.txt").write_text("[spflow.pipelines]\nexiting = exiting_pipeline\n")
    with pytest.warns(spflow.PluginWarning,
                      match=r"pipeline 'exiting' of plugin spflow-pipes 0.1 failed to import \(exiting_pipeline\): "
                            r"SystemExit\(4\)"):
        names = [info.name for info in available_pipelines()]
    assert "exiting" not in names and "workflow" in names


RAISING_LIFECYCLE = '''
import spflow

@spflow.hookimpl
def spflow_node_end(node, stage, seconds, cached):
    raise RuntimeError("dashboard unreachable")
'''

COUNTING_LIFECYCLE = '''
import spflow

ENDS = []

@spflow.hookimpl
def spflow_node_end(node, stage, seconds, cached):
    ENDS.append(node)
'''


def test_a_raising_lifecycle_hook_warns_once_and_the_run_goes_on(site, tmp_path):
    site("raising_lifecycle", RAISING_LIFECYCLE)
    counting = site("counting", COUNTING_LIFECYCLE)
    registry = get_registry()
    path = tmp_path / "in.nc"
    xr.Dataset({"y": ("x", [3.0, 4.0], {"units": "m"})}).to_netcdf(path)
    p = spflow.Pipeline("lifecycle")
    p.add_data("x", xr.Dataset({"y": ("x", [1.0, 2.0], {"units": "m"})}))
    p.add("r1", "load_netcdf", params={"path": str(path)})
    with pytest.warns(spflow.PluginWarning) as caught:
        result = spflow.run(p, cache=tmp_path / "cache")
    messages = [str(w.message) for w in caught if issubclass(w.category, spflow.PluginWarning)]
    assert len(messages) == 1, messages  # two nodes ended, one warning
    assert messages[0].startswith("plugin 'raising_lifecycle' (plug_raising_lifecycle_")
    assert "hook spflow_node_end raised RuntimeError: dashboard unreachable; spflow goes on" in messages[0]
    assert sorted(result.executed) == ["r1", "x"]
    assert sorted(sys.modules[counting].ENDS) == ["r1", "x"]  # the healthy plugin saw every node
    assert registry is get_registry()

