"""The plugin guide (docs/plugins.md) documents every hook specification with its exact signature, and no other."""

import inspect
import re
from pathlib import Path

from spflow.core.hookspecs import SpflowHookSpecs

GUIDE = Path(__file__).resolve().parents[2] / "docs" / "plugins.md"


def _specs() -> dict[str, str]:
    out = {}
    for name, func in inspect.getmembers(SpflowHookSpecs, inspect.isfunction):
        params = [p for p in inspect.signature(func).parameters if p != "self"]
        out[name] = f"{name}({', '.join(params)})"
    return out


def test_every_hookspec_is_documented_with_its_signature():
    text = GUIDE.read_text()
    specs = _specs()
    assert specs, "no hook specifications found"
    for name, signature in specs.items():
        assert f"`{signature}`" in text, f"docs/plugins.md lacks the hook signature `{signature}`"
    documented = set(re.findall(r"`(spflow_\w+)\(", text))
    assert documented == set(specs), f"documented hooks {sorted(documented)} != specifications {sorted(specs)}"
