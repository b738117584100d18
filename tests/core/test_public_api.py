"""``spflow.__all__`` equals exactly the names documented in docs/api.md, and each is importable."""

from pathlib import Path

import spflow


def test_all_equals_documented_public_names():
    doc = (Path(__file__).parents[2] / "docs" / "api.md").read_text()
    documented = {line.split("`")[1] for line in doc.splitlines() if line.startswith("- `")}
    assert set(spflow.__all__) == documented
    assert len(spflow.__all__) == len(set(spflow.__all__))
    for name in spflow.__all__:
        assert hasattr(spflow, name), name
