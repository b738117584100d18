"""Sub-commands come through the plugin hook spflow_register_commands: spflow's own diagnose / export / compare /
init / check do, a plugin's command runs from ``spflow.cli.main``, and a name already taken is refused."""

import pytest

import spflow
from spflow.cli import main
from spflow.core.errors import PluginError
from spflow.core.plugins import CORE_COMMANDS, get_commands


def test_the_builtin_commands_come_through_the_hook():
    commands = get_commands()
    assert {"diagnose", "export", "compare", "init", "check"} <= set(commands)
    assert not set(commands) & set(CORE_COMMANDS)
    assert commands["diagnose"].provider == "spflow.plugins.gap.command"


class _Hello:
    calls: list = []

    @staticmethod
    def add_parser(sub):
        p = sub.add_parser("hello", help="say hello")
        p.add_argument("--name", default="world")

    @staticmethod
    def run(args):
        _Hello.calls.append((args.command, args.name))
        print(f"hello {args.name}")
        return 0

    @spflow.hookimpl
    def spflow_register_commands(self, register):
        register(("hello",), self.add_parser, self.run)


def test_a_plugins_command_runs_from_the_cli(capsys):
    spflow.register_plugin(_Hello(), name="hello_plugin")
    try:
        assert main(["hello", "--name", "lab"]) == 0
        assert _Hello.calls[-1] == ("hello", "lab") and "hello lab" in capsys.readouterr().out
        assert main(["list", "commands"]) == 0
        assert "hello (from" in capsys.readouterr().out
    finally:
        spflow.unregister_plugin("hello_plugin")
    with pytest.raises(SystemExit):
        main(["hello"])  # gone with its plugin: argparse rejects the unknown command


@pytest.mark.parametrize("name", ["run", "diagnose"])
def test_a_taken_name_is_refused(name):
    class Clash:
        @spflow.hookimpl
        def spflow_register_commands(self, register):
            register((name,), _Hello.add_parser, _Hello.run)

    spflow.register_plugin(Clash(), name="clash")
    try:
        with pytest.raises(PluginError, match=f"command '{name}' is already taken"):
            get_commands()
    finally:
        spflow.unregister_plugin("clash")
