"""Parse the keyword tables of an ECLIPSE deck written by the OPM export (test helper, independent of the
exporter): ``{KEYWORD: [rows of floats]}`` for the table keywords, records split on ``/``."""

import re


def keyword_records(text: str, keyword: str) -> list[list[list[str]]]:
    """Every occurrence of ``keyword``: its records (up to the terminating ``/``), each a list of token rows."""
    lines = [ln.split("--")[0] for ln in text.splitlines()]
    out, i = [], 0
    while i < len(lines):
        if lines[i].strip() == keyword:
            body = []
            i += 1
            while i < len(lines) and not re.fullmatch(r"[A-Z][A-Z0-9]*", lines[i].strip()):
                body.append(lines[i])
                i += 1
            out.append(body)
        else:
            i += 1
    return out


def table(text: str, keyword: str) -> list[list[float]]:
    """The single table of ``keyword`` as rows of floats (one row per line, the final ``/`` dropped)."""
    (body,) = keyword_records(text, keyword)
    rows = []
    for line in body:
        tokens = line.replace("/", " ").split()
        if tokens:
            rows.append([float(t) for t in tokens])
    return rows


def expand(tokens: list[str]) -> list[str]:
    """ECLIPSE repeat counts: ``3*0.2`` -> three ``0.2``; ``2*`` -> two defaults (``None``)."""
    out = []
    for t in tokens:
        m = re.fullmatch(r"(\d+)\*(.*)", t)
        if m:
            out += [m.group(2) or None] * int(m.group(1))
        else:
            out.append(t)
    return out
