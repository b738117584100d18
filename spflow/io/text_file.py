"""Reading a user's text file (a CSV coreflood, a study file): UTF-8 only, with one clear error for an empty, UTF-16,
binary or otherwise undecodable file, naming the file and what it should be."""

from __future__ import annotations

from pathlib import Path

__all__ = ["read_utf8_text"]


def read_utf8_text(path: Path, where: str, kind: str, empty_hint: str) -> str:
    """The text of ``path`` decoded as UTF-8 (a BOM is dropped). ``ValueError`` starting with ``where`` for an empty
    file (``empty_hint`` says what it needs), a UTF-16 one, a binary one (a NUL byte) or undecodable bytes; ``kind``
    names the expected content, e.g. ``"UTF-8 CSV text"``."""
    raw = Path(path).read_bytes()
    if not raw.strip():
        raise ValueError(f"{where}: empty file; {empty_hint}")
    if raw[:2] in (b"\xff\xfe", b"\xfe\xff"):
        raise ValueError(f"{where}: the file is UTF-16 encoded; save it as {kind}")
    nul = raw.find(b"\x00")
    if nul >= 0:
        raise ValueError(f"{where}: binary file, not UTF-8 text (a NUL byte at byte {nul}); expected {kind}")
    try:
        return raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise ValueError(f"{where}: not UTF-8 text (undecodable byte at position {exc.start}); expected {kind}") \
            from None
