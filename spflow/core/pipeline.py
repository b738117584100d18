"""A pipeline: a networkx DAG of named nodes, each running one registered stage.

>>> p = Pipeline("prior")
>>> p.add("design", "lhs_design", params={"samples": 32, "seed": 1})
>>> p.add("sim", "forward", inputs={"design": "design"}, params={"experiments": ["BCF1"]})

Swapping an implementation is naming another registered stage for the same node (``p.set_stage("sim", "other")``);
no other node changes. In-memory Datasets enter through ``add_data`` and are content-hashed.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from typing import Any

import networkx as nx
import xarray as xr

from .errors import PipelineError

__all__ = ["Pipeline", "Node"]


@dataclass
class Node:
    """One node: which stage it runs, with which params, wired to which upstream nodes (port -> node)."""

    name: str
    stage: str
    params: dict[str, Any] = field(default_factory=dict)
    inputs: dict[str, str] = field(default_factory=dict)
    dataset: xr.Dataset | None = None  # only for data nodes (stage "data")


class Pipeline:
    """A DAG of stage nodes wired output -> input."""

    def __init__(self, name: str):
        if not name or not name.replace("_", "").replace("-", "").isalnum():
            raise PipelineError(f"pipeline name must be a non-empty identifier (letters, digits, _ or -), got {name!r}")
        self.name = name
        self.nodes: dict[str, Node] = {}

    # -- building ---------------------------------------------------------------------------------------------------
    def add(self, node: str, stage: str, *, params: Mapping[str, Any] | None = None,
            inputs: Mapping[str, str] | None = None) -> Pipeline:
        """Add ``node`` running registered stage ``stage``; ``inputs`` maps the stage's input ports to upstream nodes."""
        if node in self.nodes:
            raise PipelineError(f"pipeline {self.name!r} already has a node {node!r}")
        if not node or "/" in node:
            raise PipelineError(f"node names must be non-empty and contain no '/', got {node!r}")
        self.nodes[node] = Node(node, stage, dict(params or {}), dict(inputs or {}))
        return self

    def add_data(self, node: str, dataset: xr.Dataset) -> Pipeline:
        """Add an external Dataset as a source node; its provenance key is its canonical content hash."""
        if not isinstance(dataset, xr.Dataset):
            raise PipelineError(f"add_data({node!r}): expected an xarray.Dataset, got {type(dataset).__name__}")
        self.add(node, "data")
        self.nodes[node].dataset = dataset.load()
        return self

    def include(self, other: Pipeline, prefix: str, *, share: Iterable[str] = ()) -> Pipeline:
        """Copy every node of ``other`` into this pipeline as ``<prefix>.<node>`` (wiring renamed alike).

        ``share`` names nodes of ``other`` that are *not* copied: their consumers are wired to the node of the same
        name already in this pipeline (e.g. one ``observations`` node feeding two included sub-pipelines). A node
        keeps its provenance key under the new name, so results cached by running ``other`` alone are reused.
        """
        shared = set(share)
        for name in shared:
            other._node(name)
            self._node(name)

        def renamed(name: str) -> str:
            return name if name in shared else f"{prefix}.{name}"

        for node in other.nodes.values():
            if node.name in shared:
                continue
            if node.dataset is not None:
                self.add_data(renamed(node.name), node.dataset)
                continue
            self.add(renamed(node.name), node.stage, params=node.params,
                     inputs={port: renamed(up) for port, up in node.inputs.items()})
        return self

    def set_stage(self, node: str, stage: str, params: Mapping[str, Any] | None = None) -> Pipeline:
        """Swap the stage a node runs (e.g. surrogate ``pce`` -> ``pck``), keeping its wiring."""
        self._node(node).stage = stage
        self._node(node).params = dict(params or {})
        return self

    def set_params(self, node: str, **params: Any) -> Pipeline:
        """Update some parameters of a node."""
        self._node(node).params.update(params)
        return self

    def _node(self, node: str) -> Node:
        try:
            return self.nodes[node]
        except KeyError:
            raise PipelineError(f"pipeline {self.name!r} has no node {node!r}; nodes: {', '.join(self.nodes)}") from None

    # -- graph queries ----------------------------------------------------------------------------------------------
    def graph(self) -> nx.DiGraph:
        """The DAG (edges upstream -> node, attribute ``port``); raises on unknown upstream nodes or cycles."""
        g = nx.DiGraph()
        g.add_nodes_from(self.nodes)
        for node in self.nodes.values():
            for port, upstream in node.inputs.items():
                if upstream not in self.nodes:
                    raise PipelineError(
                        f"node {node.name!r} input port {port!r} is wired to unknown node {upstream!r}; "
                        f"nodes: {', '.join(self.nodes)}"
                    )
                g.add_edge(upstream, node.name, port=port)
        if not nx.is_directed_acyclic_graph(g):
            cycle = " -> ".join(u for u, _ in nx.find_cycle(g))
            raise PipelineError(f"pipeline {self.name!r} has a cycle: {cycle}")
        return g

    def order(self) -> list[str]:
        """Nodes in a deterministic topological order."""
        return list(nx.lexicographical_topological_sort(self.graph()))

    def _closure(self, nodes: Iterable[str], relatives) -> set[str]:
        g = self.graph()
        out: set[str] = set()
        for n in nodes:
            self._node(n)
            out |= relatives(g, n) | {n}
        return out

    def upstream_of(self, nodes: Iterable[str]) -> set[str]:
        """The given nodes and all their ancestors (Kedro's ``to_nodes`` slice)."""
        return self._closure(nodes, nx.ancestors)

    def downstream_of(self, nodes: Iterable[str]) -> set[str]:
        """The given nodes and all their descendants (Kedro's ``from_nodes`` slice)."""
        return self._closure(nodes, nx.descendants)

    def __repr__(self) -> str:
        parts = [f"{n.name}={n.stage}" + (f"<-{n.inputs}" if n.inputs else "") for n in self.nodes.values()]
        return f"Pipeline({self.name!r}: {', '.join(parts)})"
