"""Third-party plugins: a real package declaring the entry-point group ``spflow`` is built and installed into a
temporary directory; its stage then appears in ``spflow list`` and runs in a pipeline, exactly like built-ins."""

import os
import subprocess
import sys
from pathlib import Path

import pytest

import spflow
from spflow.core.plugins import get_registry

PLUGIN_PYPROJECT = """
[build-system]
requires = ["setuptools"]
build-backend = "setuptools.build_meta"

[project]
name = "spflow-toyplugin"
version = "0.3.0"

[project.entry-points.spflow]
toyplugin = "spflow_toyplugin"
"""

PLUGIN_MODULE = '''
"""A third-party spflow plugin: one stage that doubles a series."""
import numpy as np
import xarray as xr
import spflow


class Ramp(spflow.Stage):
    name = "thirdparty_ramp"
    description = "ramp from a third-party package"
    output = spflow.DatasetSchema(variables={"y": spflow.Variable(("x",), units="m")})
    params = {"n": spflow.Param(int, 4, bounds=(1, 100))}

    def run(self, ctx):
        return xr.Dataset({"y": ("x", np.arange(self.params["n"], dtype=float) * 2.0, {"units": "m"})})


@spflow.hookimpl
def spflow_register_stages(register):
    register(Ramp)
'''

PIPELINE = """
import spflow
pipeline = spflow.Pipeline("third").add("r", "thirdparty_ramp", params={"n": 3})

def report(result, outdir):
    return ["values " + " ".join(str(v) for v in result["r"]["y"].values)]
"""


@pytest.fixture(scope="module")
def installed_plugin(tmp_path_factory):
    root = tmp_path_factory.mktemp("plugin")
    src = root / "src"
    (src / "spflow_toyplugin").mkdir(parents=True)
    (src / "pyproject.toml").write_text(PLUGIN_PYPROJECT)
    (src / "spflow_toyplugin" / "__init__.py").write_text(PLUGIN_MODULE)
    target = root / "site"
    subprocess.run(
        [sys.executable, "-m", "pip", "install", "--quiet", "--no-deps", "--no-index", "--no-build-isolation",
         "--target", str(target), str(src)],
        check=True,
    )
    assert list(target.glob("spflow_toyplugin-0.3.0.dist-info/entry_points.txt"))
    return target


def _env(site: Path, **extra) -> dict:
    env = dict(os.environ)
    env.pop("SPFLOW_DISABLE_PLUGINS", None)
    env["PYTHONPATH"] = os.pathsep.join([str(site), env.get("PYTHONPATH", "")])
    env.update(extra)
    return env


def test_installed_plugin_is_listed_and_runs(installed_plugin, tmp_path):
    cli = [sys.executable, "-m", "spflow.cli"]
    listed = subprocess.run(cli + ["list", "stages"], env=_env(installed_plugin), capture_output=True, text=True,
                            check=True)
    assert "thirdparty_ramp (version 1, from spflow_toyplugin): ramp from a third-party package" in listed.stdout
    assert "load_netcdf" in listed.stdout  # built-ins come through the same hooks
    (tmp_path / "third.py").write_text(PIPELINE)
    ran = subprocess.run(cli + ["run", "third.py", "--cache", "c"], cwd=tmp_path, env=_env(installed_plugin),
                         capture_output=True, text=True)
    assert ran.returncode == 0, ran.stderr
    assert "values 0.0 2.0 4.0" in ran.stdout


def test_disabled_plugin_is_not_loaded(installed_plugin):
    listed = subprocess.run([sys.executable, "-m", "spflow.cli", "list", "stages"],
                            env=_env(installed_plugin, SPFLOW_DISABLE_PLUGINS="toyplugin"),
                            capture_output=True, text=True, check=True)
    assert "thirdparty_ramp" not in listed.stdout


def test_duplicate_stage_names_are_refused():
    class A(spflow.Stage):
        name = "load_netcdf"

    class Dup:
        @spflow.hookimpl
        def spflow_register_stages(self, register):
            register(A)

    spflow.register_plugin(Dup(), name="dup")
    try:
        with pytest.raises(spflow.PluginError, match="stage name 'load_netcdf' registered twice"):
            get_registry()
    finally:
        spflow.unregister_plugin("dup")


def test_non_stage_registration_is_refused():
    class Bad:
        @spflow.hookimpl
        def spflow_register_stages(self, register):
            register(object)

    spflow.register_plugin(Bad(), name="bad")
    try:
        with pytest.raises(spflow.PluginError, match="expected a Stage subclass"):
            get_registry()
    finally:
        spflow.unregister_plugin("bad")


def test_misspelled_hook_is_caught():
    class Typo:
        @spflow.hookimpl
        def spflow_register_stage(self, register):  # missing "s"
            pass

    with pytest.raises(Exception, match="unknown hook 'spflow_register_stage'"):
        spflow.register_plugin(Typo(), name="typo")
        get_registry()
    spflow.unregister_plugin("typo")


def test_hookspecs_are_documented():
    """Every hook in the spec appears in docs/plugins.md (the plugin guide), and vice versa."""
    from spflow.core.hookspecs import SpflowHookSpecs

    hooks = {n for n in vars(SpflowHookSpecs) if n.startswith("spflow_")}
    doc = (Path(__file__).parents[2] / "docs" / "plugins.md").read_text()
    documented = {line.split("`")[1].split("(")[0] for line in doc.splitlines() if line.startswith("- `spflow_")}
    assert hooks == documented
