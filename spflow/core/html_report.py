"""A self-contained HTML report of a pipeline run: the report's text, every figure embedded, and provenance.

A pipeline module's ``report(result, outdir)`` writes figures into ``outdir`` and returns the lines to print: either
a list of lines (one section holding every PNG of ``outdir``), or a mapping ``{sub-directory: lines}`` (one section
per sub-directory of ``outdir`` with the PNGs found there); a line may be a :class:`~spflow.core.report_table.Table`.
:func:`write_html_report` turns that into ``outdir/report.html`` -- figures inlined as base64 PNG, so the file can be
mailed or archived alone -- with the pipeline's DAG drawn (an inline SVG, :mod:`spflow.core.dag_svg`: nodes coloured
by ran / cached / failed / not run), the table of every node (stage, version, parameters, provenance key, whether it
ran or came from the cache, seconds) and the versions of spflow, Python and the libraries its results depend on.
Every table is an HTML ``<table>`` whose header carries the units; text lines wrap (nothing is cut off), and every
warning line of a section (``WARNING ...``, or a line saying the data reject the model) is repeated as a call-out
at the top of its section, before the section's text, tables and figures.
"""

from __future__ import annotations

import base64
import datetime
import html
import json
import re
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path

from .report_table import Table

__all__ = ["Section", "sections_from", "provenance_rows", "software_versions", "write_html_report"]

#: The distributions whose versions a report records (spflow's dependencies that shape its results).
_SOFTWARE = ("spflow", "numpy", "scipy", "xarray", "netCDF4", "pluggy", "networkx", "joblib", "numba", "chaospy",
             "SALib", "scikit-learn", "GPy", "pymoo", "moocore", "emcee", "arviz", "matplotlib")
_WARNING = re.compile(r"^\s*WARNING\b|data reject the model|the data reject", re.IGNORECASE)
_LEADING_WARNING = re.compile(r"^WARNING\b:?\s*", re.IGNORECASE)  # the call-out says "Warning." itself

_CSS = """
body { font-family: system-ui, sans-serif; margin: 2em auto; max-width: 1200px; color: #222; }
h1 { border-bottom: 2px solid #446; } h2 { margin-top: 2em; border-bottom: 1px solid #aab; }
pre { background: #f6f6f9; padding: 0.8em; font-size: 0.85em; white-space: pre-wrap; overflow-wrap: anywhere; }
p.warning { background: #fff3cd; border-left: 5px solid #c90; padding: 0.6em 0.9em; font-weight: 600; }
figure { margin: 1.5em 0; } figure img { max-width: 100%; border: 1px solid #ddd; }
figcaption { font-size: 0.9em; color: #555; }
table { border-collapse: collapse; font-size: 0.8em; margin: 0.8em 0; } td, th { border: 1px solid #ccd;
padding: 0.3em 0.5em; vertical-align: top; } th { background: #eef; text-align: left; } th .unit { font-weight: normal;
color: #446; } td.num { text-align: right; font-variant-numeric: tabular-nums; } caption { text-align: left;
font-weight: 600; padding: 0.3em 0; } td.params { font-family: monospace; max-width: 40em; word-break: break-all; }
nav a { margin-right: 1em; } div.dag { overflow-x: auto; border: 1px solid #ddd; padding: 0.5em; background: #fcfcfe; }
"""


@dataclass
class Section:
    """One part of the report: a title, the text lines the pipeline printed, and its figures."""

    title: str
    lines: list[str | Table] = field(default_factory=list)
    figures: list[Path] = field(default_factory=list)


def _title(name: str) -> str:
    return name.replace("_", " ").strip().capitalize() or "Summary"


def sections_from(outdir: Path, lines: list[str | Table] | Mapping[str, list[str | Table]] | None) -> list[Section]:
    """Sections of a report function's return value (module docstring) with the PNGs it wrote."""
    outdir = Path(outdir)
    if lines is None or not isinstance(lines, Mapping):
        return [Section("Summary", list(lines or []), sorted(outdir.glob("*.png")))]
    return [Section(_title(sub), list(text), sorted((outdir / sub).glob("*.png"))) for sub, text in lines.items()]


def caption(path: Path) -> str:
    """``fig_3_10_pareto_fronts.png`` -> ``Fig. 3.10: pareto fronts``; other names -> the words of the stem."""
    match = re.match(r"fig_(\d+)_(\d+)_?(.*)", path.stem)
    if match:
        chapter, number, rest = match.groups()
        return f"Fig. {chapter}.{number}: {rest.replace('_', ' ')}".rstrip(": ")
    match = re.match(r"fig_([a-e])(\d+)_?(.*)", path.stem)
    if match:
        appendix, number, rest = match.groups()
        return f"Fig. {appendix.upper()}.{number}: {rest.replace('_', ' ')}"
    return path.stem.replace("_", " ")


def provenance_rows(result) -> list[dict]:
    """Per node of a :class:`~spflow.core.executor.RunResult`: stage, version, params, key, ran/cached, seconds."""
    rows = []
    for node, key in result.keys.items():
        record = result.store.record(key) if result.store.has(key) else {}
        rows.append({
            "node": node, "stage": record.get("stage", "?"), "version": record.get("version", "?"),
            "params": record.get("params", {}), "key": key,
            "state": "ran" if node in result.executed else "cached", "seconds": record.get("seconds"),
        })
    return rows


def software_versions() -> dict[str, str]:
    """``{name: version}`` of Python and of every distribution in ``_SOFTWARE`` (``"not installed"`` if absent)."""
    import platform
    from importlib.metadata import PackageNotFoundError, version

    found = {"Python": platform.python_version()}
    for name in _SOFTWARE:
        try:
            found[name] = version(name)
        except PackageNotFoundError:
            found[name] = "not installed"
    return found


def _figure_html(path: Path) -> str:
    data = base64.b64encode(path.read_bytes()).decode("ascii")
    text = html.escape(caption(path))
    return (f'<figure><img alt="{text}" src="data:image/png;base64,{data}">'
            f"<figcaption>{text} <small>({html.escape(path.name)})</small></figcaption></figure>")


def _header_html(table: Table) -> str:
    return "".join(f"<th>{html.escape(c)}" + (f" <span class='unit'>[{html.escape(u)}]</span>" if u else "") + "</th>"
                   for c, u in zip(table.columns, table.units))


def table_html(table: Table) -> str:
    """An HTML ``<table>``: caption, header with units, one row per row (numbers right-aligned)."""
    rows = []
    for values, cells in zip(table.rows, table.cells()):
        tds = [f"<td class='num'>{html.escape(c)}</td>" if isinstance(v, (int, float)) and not isinstance(v, bool)
               else f"<td>{html.escape(c)}</td>" for v, c in zip(values, cells)]
        rows.append(f"<tr>{''.join(tds)}</tr>")
    caption = f"<caption>{html.escape(table.title)}</caption>" if table.title else ""
    return f"<table>{caption}<thead><tr>{_header_html(table)}</tr></thead><tbody>{''.join(rows)}</tbody></table>"


def _provenance_html(rows: list[dict]) -> str:
    head = ("<tr><th>node</th><th>stage</th><th>version</th><th>run</th><th>time <span class='unit'>[s]</span></th>"
            "<th>key</th><th>params</th></tr>")
    body = []
    for r in rows:
        seconds = f"{r['seconds']:.2f}" if isinstance(r["seconds"], (int, float)) else ""
        params = html.escape(json.dumps(r["params"], sort_keys=True, default=str))
        body.append(f"<tr><td>{html.escape(r['node'])}</td><td>{html.escape(str(r['stage']))}</td>"
                    f"<td>{html.escape(str(r['version']))}</td><td>{r['state']}</td><td class='num'>{seconds}</td>"
                    f"<td><code>{r['key'][:16]}</code></td><td class='params'><details><summary>{len(r['params'])} "
                    f"parameter(s)</summary>{params}</details></td></tr>")
    return f"<table><thead>{head}</thead><tbody>{''.join(body)}</tbody></table>"


def _section_body_html(items: list[str | Table]) -> list[str]:
    """Runs of text lines as wrapped ``<pre>`` blocks, tables as ``<table>`` elements, in their order."""
    parts, text = [], []
    for item in [*items, None]:
        if isinstance(item, str):
            text.append(item)
            continue
        if text:
            parts.append(f"<pre>{html.escape(chr(10).join(text))}</pre>")
            text = []
        if isinstance(item, Table):
            parts.append(table_html(item))
    return parts


def write_html_report(path: Path, title: str, sections: list[Section], provenance: list[dict],
                      dag: str = "") -> Path:
    """Write the report (module docstring) to ``path`` atomically and return it; ``dag``: the pipeline's DAG as SVG
    markup (:func:`spflow.core.dag_svg.dag_svg`), drawn above the provenance table."""
    path = Path(path)
    versions = software_versions()
    anchors = [f"s{i}" for i in range(len(sections))]
    nav = "".join(f'<a href="#{a}">{html.escape(s.title)}</a>' for a, s in zip(anchors, sections))
    parts = [f"<!DOCTYPE html><html lang='en'><head><meta charset='utf-8'><title>{html.escape(title)}</title>"
             f"<style>{_CSS}</style></head><body><h1>{html.escape(title)}</h1>",
             f"<p>Written {datetime.datetime.now().isoformat(timespec='seconds')} by spflow "
             f"{html.escape(versions['spflow'])}.</p>",
             f"<nav>{nav}<a href='#provenance'>Provenance</a><a href='#software'>Software</a></nav>"]
    for anchor, section in zip(anchors, sections):
        parts.append(f"<section id='{anchor}'><h2>{html.escape(section.title)}</h2>")
        parts.extend(f"<p class='warning' role='alert'><strong>Warning.</strong> "
                     f"{html.escape(_LEADING_WARNING.sub('', line.strip()))}</p>" for line in section.lines
                     if isinstance(line, str) and _WARNING.search(line))
        parts.extend(_section_body_html(section.lines))
        parts.extend(_figure_html(f) for f in section.figures)
        parts.append("</section>")
    parts.append("<h2 id='provenance'>Provenance</h2>")
    if dag:
        parts.append(f"<p>The pipeline: each box a node (its name and stage), columns in dependency order, filled by "
                     f"what this run did with it.</p><div class='dag'>{dag}</div>")
    parts.append("<p>Every node of the run: the stage it ran, its parameters and the provenance key its result is "
                 "cached under.</p>")
    parts.append(_provenance_html(provenance))
    rows = "".join(f"<tr><td>{html.escape(k)}</td><td>{html.escape(v)}</td></tr>" for k, v in versions.items())
    parts.append(f"<h2 id='software'>Software</h2><table><tr><th>package</th><th>version</th></tr>{rows}</table>")
    parts.append("</body></html>")
    tmp = path.with_suffix(".html.tmp")
    tmp.write_text("\n".join(parts), encoding="utf-8")
    tmp.replace(path)
    return path
