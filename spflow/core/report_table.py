"""A table in a pipeline's report: named columns with their units, rows of values.

A pipeline module's ``report(result, outdir)`` may return :class:`Table` objects among its lines. The terminal gets
the table as aligned text (:meth:`Table.lines`), ``report.html`` an HTML ``<table>`` with the units in the header
(:mod:`spflow.core.html_report`). Units are UDUNITS strings; a column whose unit differs per row (a parameter table)
has a ``unit`` column instead, filled from the data's ``param_unit`` coordinate or the space's ``unit`` variable.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

__all__ = ["Table", "format_cell", "text_lines"]


def format_cell(value: Any) -> str:
    """A cell as text: floats to 4 significant digits (NaN as ``-``), the rest with ``str``."""
    if isinstance(value, bool) or value is None:
        return "" if value is None else str(value)
    if isinstance(value, float):
        return "-" if math.isnan(value) else f"{value:.4g}"
    return str(value)


@dataclass
class Table:
    """``columns`` (names), ``units`` (one UDUNITS string per column, ``""`` where none applies) and ``rows``."""

    columns: list[str]
    rows: list[list[Any]]
    units: list[str] = field(default_factory=list)
    title: str = ""

    def __post_init__(self) -> None:
        self.units = list(self.units) or [""] * len(self.columns)
        if len(self.units) != len(self.columns):
            raise ValueError(f"table {self.title!r}: {len(self.columns)} columns but {len(self.units)} units")
        bad = [i for i, row in enumerate(self.rows) if len(row) != len(self.columns)]
        if bad:
            raise ValueError(f"table {self.title!r}: row {bad[0]} has {len(self.rows[bad[0]])} cells, the table has "
                             f"{len(self.columns)} columns {self.columns}")

    def headers(self) -> list[str]:
        """Column headers with their units: ``"mean [kPa]"``; a column without a unit keeps its name."""
        return [f"{c} [{u}]" if u else c for c, u in zip(self.columns, self.units)]

    def cells(self) -> list[list[str]]:
        return [[format_cell(v) for v in row] for row in self.rows]

    def lines(self) -> list[str]:
        """The table as aligned text lines (title, header, rows) for the terminal."""
        grid = [self.headers(), *self.cells()]
        widths = [max(len(r[j]) for r in grid) for j in range(len(self.columns))]
        text = ["  ".join(cell.ljust(w) for cell, w in zip(row, widths)).rstrip() for row in grid]
        return ([self.title] if self.title else []) + text


def text_lines(items: Sequence[str | Table]) -> list[str]:
    """Report items as plain text lines: each table expanded to its aligned lines."""
    out: list[str] = []
    for item in items:
        out.extend(item.lines() if isinstance(item, Table) else [item])
    return out

