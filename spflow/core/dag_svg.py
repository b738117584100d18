"""The pipeline DAG drawn as an inline SVG for the HTML report: topological generations as columns, one box per node
coloured by what the run did with it, edges from each input to its consumer.

Written by hand (no plotting library): a layered layout -- column = the node's topological generation
(:func:`networkx.topological_generations`), nodes of a column in pipeline order -- boxes sized to their labels, and
cubic edges between the right side of a producer and the left side of its consumer. An edge that skips columns runs
in its own lane above the boxes, so that it never crosses a box it does not connect. The drawing scales down to the
page width (``viewBox``), never above its natural size.
"""

from __future__ import annotations

import html
from collections.abc import Mapping

import networkx as nx

__all__ = ["STATE_COLOURS", "dag_svg"]

#: Fill colour of a node per state: ``ran`` (computed in this run), ``cached`` (reused from the store), ``failed``,
#: ``not run`` (outside ``--until``/``--only``, or after a failure).
STATE_COLOURS = {"ran": "#b7e4b0", "cached": "#bcd4f6", "failed": "#f4a9a8", "not run": "#e4e4e4"}

_CHAR_W, _BOX_H, _GAP_X, _GAP_Y, _PAD, _LANE = 7.0, 38, 70, 16, 12, 9


def _box_width(node: str, stage: str) -> float:
    return max(len(node), len(stage) + 2) * _CHAR_W + 2 * _PAD


def dag_svg(graph: nx.DiGraph, stages: Mapping[str, str], states: Mapping[str, str]) -> str:
    """SVG markup of ``graph`` (a pipeline's DAG: edges producer -> consumer), each node labelled with its name and
    ``stages[node]`` and filled by ``STATE_COLOURS[states[node]]`` (a missing state is ``not run``); a legend
    follows. Every node is one ``<g class="dag-node" data-node=...>``."""
    order = {n: i for i, n in enumerate(graph.nodes)}
    columns = [sorted(gen, key=order.__getitem__) for gen in nx.topological_generations(graph)]
    column_of = {n: c for c, col in enumerate(columns) for n in col}
    long_edges = [(u, v) for u, v in graph.edges if column_of[v] - column_of[u] > 1]
    lanes_h = len(long_edges) * _LANE + (_LANE if long_edges else 0)
    widths = [max((_box_width(n, stages.get(n, "")) for n in col), default=0.0) for col in columns]
    height = max((len(col) for col in columns), default=0) * (_BOX_H + _GAP_Y) - _GAP_Y
    pos: dict[str, tuple[float, float, float]] = {}  # node -> (x, y, width)
    x = _PAD
    for col, width in zip(columns, widths):
        top = _PAD + lanes_h + (height - (len(col) * (_BOX_H + _GAP_Y) - _GAP_Y)) / 2  # centre short columns
        for k, node in enumerate(col):
            pos[node] = (x, top + k * (_BOX_H + _GAP_Y), width)
        x += width + _GAP_X
    total_w = max(x - _GAP_X + _PAD, 320.0)
    legend_y = lanes_h + height + 2 * _PAD + 6
    parts = [f'<svg xmlns="http://www.w3.org/2000/svg" class="dag" viewBox="0 0 {total_w:.0f} {legend_y + 24:.0f}" '
             f'style="width: 100%; max-width: {total_w:.0f}px; height: auto" role="img" aria-label="pipeline DAG" '
             'font-family="system-ui, sans-serif" font-size="12">',
             '<defs><marker id="dag-arrow" viewBox="0 0 10 10" refX="10" refY="5" markerWidth="7" markerHeight="7" '
             'orient="auto-start-reverse"><path d="M 0 0 L 10 5 L 0 10 z" fill="#667"/></marker></defs>']
    lane = {edge: _PAD + k * _LANE for k, edge in enumerate(long_edges)}
    for u, v in graph.edges:
        (x0, y0, w0), (x1, y1, _) = pos[u], pos[v]
        sx, sy, ex, ey = x0 + w0, y0 + _BOX_H / 2, x1, y1 + _BOX_H / 2
        if (u, v) in lane:  # up into its lane, along it over the columns in between, down into the consumer
            ly, bend = lane[(u, v)], _GAP_X / 2
            d = (f"M {sx:.1f} {sy:.1f} C {sx + bend:.1f} {sy:.1f}, {sx + bend / 2:.1f} {ly:.1f}, {sx + bend:.1f} "
                 f"{ly:.1f} L {ex - bend:.1f} {ly:.1f} C {ex - bend / 2:.1f} {ly:.1f}, {ex - bend:.1f} {ey:.1f}, "
                 f"{ex:.1f} {ey:.1f}")
        else:
            mid = (sx + ex) / 2
            d = f"M {sx:.1f} {sy:.1f} C {mid:.1f} {sy:.1f}, {mid:.1f} {ey:.1f}, {ex:.1f} {ey:.1f}"
        parts.append(f'<path class="dag-edge" d="{d}" fill="none" stroke="#667" stroke-width="1.2" '
                     'marker-end="url(#dag-arrow)"/>')
    for node, (nx0, ny0, width) in pos.items():
        state = states.get(node, "not run")
        label, stage = html.escape(node), html.escape(stages.get(node, ""))
        parts.append(f'<g class="dag-node" data-node="{label}" data-state="{html.escape(state)}">'
                     f'<title>{label} (stage {stage}): {html.escape(state)}</title>'
                     f'<rect x="{nx0:.1f}" y="{ny0:.1f}" width="{width:.1f}" height="{_BOX_H}" rx="6" '
                     f'fill="{STATE_COLOURS.get(state, STATE_COLOURS["not run"])}" stroke="#445" stroke-width="1"/>'
                     f'<text x="{nx0 + width / 2:.1f}" y="{ny0 + 16:.1f}" text-anchor="middle" font-weight="600">'
                     f'{label}</text><text x="{nx0 + width / 2:.1f}" y="{ny0 + 30:.1f}" text-anchor="middle" '
                     f'fill="#445" font-size="11">{stage}</text></g>')
    lx = _PAD
    for state, colour in STATE_COLOURS.items():
        parts.append(f'<rect x="{lx:.0f}" y="{legend_y:.0f}" width="14" height="14" rx="3" fill="{colour}" '
                     f'stroke="#445"/><text x="{lx + 20:.0f}" y="{legend_y + 11:.0f}">{state}</text>')
        lx += 30 + len(state) * _CHAR_W
    parts.append("</svg>")
    return "".join(parts)
