"""The sources and docs cite only documents a reader of the repository has.

The project's method notes and the thesis text live outside the repository; code and docs cite the primary
literature or a page of ``docs/`` instead. This scans the package, scripts, benchmarks, tests, examples, ``docs/``
and ``README.md`` for paths out of the repository or into the notes, and names file and line of each.
"""

from __future__ import annotations

import re
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
SCANNED = ("spflow", "scripts", "benchmarks", "tests", "examples", "docs")
SUFFIXES = {".py", ".md", ".toml", ".txt", ".cfg", ".sh", ".rst"}

EXTERNAL = re.compile(
    r"shared/"  # the project's shared folder (notes, thesis seeds, the first architecture sketch)
    r"|/work/"  # an absolute path on the development machine
    r"|notes/[a-z_]+\.md"  # a note by path
    r"|[Gg]ap notes"  # the gap note by name ("gap notes §6.1")
    r"|(?<![\w/.-])(?:physics|uq|pipeline)\.md"  # the notes with no page of that name in docs/
    r"|ARCHITECTURE\.md"  # the first sketch (docs/architecture.md, lower case, is the repository's own)
)


def external_references(root: Path) -> list[str]:
    """``path:line: text`` of every line under ``root`` that points outside the repository."""
    this = Path(__file__).resolve()
    hits = []
    files = [root / "README.md"] + [p for d in SCANNED if (root / d).is_dir() for p in sorted((root / d).rglob("*"))]
    for path in files:
        if path.resolve() == this or not path.is_file() or path.suffix not in SUFFIXES:
            continue
        for number, line in enumerate(path.read_text(encoding="utf-8", errors="replace").splitlines(), 1):
            if EXTERNAL.search(line):
                hits.append(f"{path.relative_to(root)}:{number}: {line.strip()}")
    return hits


def test_no_reference_to_documents_outside_the_repository():
    hits = external_references(REPO)
    assert not hits, "references to documents outside the repository:\n" + "\n".join(hits)


def test_the_scan_finds_each_kind_of_reference(tmp_path):
    # each form the repository used to contain, planted in a copy of the layout: each is reported with its line
    planted = {
        "spflow/a.py": '"""Mean shift (gap notes §2.9)."""',
        "spflow/b.py": "# the formulas of notes/uq.md §1.2",
        "scripts/c.py": "# see ``/work/shared/notes/physics.md`` section 2",
        "tests/d.py": "# physics.md 2.6: surfactant Langmuir example",
        "docs/e.md": "see docs/architecture.md; after the sketch (`shared/ARCHITECTURE.md`) and the thesis in `../shared/seeds/`",
        "benchmarks/f.py": "# UQLab conventions (uq.md §1.1)",
    }
    for name, text in planted.items():
        (tmp_path / name).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / name).write_text(f"ok = 1\n{text}\n", encoding="utf-8")
    (tmp_path / "README.md").write_text("See docs/gap.md and docs/independent_world.md.\n", encoding="utf-8")
    (tmp_path / "docs" / "fine.md").write_text("The design follows docs/gap.md (Kennedy & O'Hagan 2001).\n",
                                               encoding="utf-8")
    hits = external_references(tmp_path)
    assert sorted(h.split(":")[0] for h in hits) == sorted(planted)
    assert all(h.split(":")[1] == "2" for h in hits)
