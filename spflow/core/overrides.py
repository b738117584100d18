"""Parameter overrides of a built pipeline (``spflow run PIPELINE --set node.param=value``), checked before any work.

``node.param=value``: the node is split from the parameter at the last dot before ``=`` (the nodes of included
pipelines, such as ``hm.calibration``, keep their dots). The value is parsed as JSON when it parses (``32``,
``0.5``, ``true``, ``["BCF1", "BCF2"]``, ``{"cells": 40}``) and is taken as a string otherwise (``BCF1``; quote it,
``'"32"'``, for the string "32"). The node must exist and its stage must declare the parameter, and the value is
validated against that declaration (:mod:`spflow.core.params`: type, range, choices); each error names the
pipeline's nodes or the stage's parameters with their allowed ranges. The value replaces the node's parameter, so it
enters that node's provenance key: exactly the node and its descendants rerun.
"""

from __future__ import annotations

import difflib
import json
from collections.abc import Iterable
from dataclasses import dataclass
from typing import Any

from .errors import ParameterError, PipelineError
from .params import validate_params
from .pipeline import Pipeline
from .plugins import get_registry

__all__ = ["Override", "parse_override", "apply_overrides"]


@dataclass(frozen=True)
class Override:
    """One applied override: the node, the parameter, the new value and the value it replaced."""

    node: str
    param: str
    value: Any
    replaced: str

    def describe(self) -> str:
        return f"--set {self.node}.{self.param}={json.dumps(self.value, default=str)} (replaces {self.replaced})"


def parse_override(text: str) -> tuple[str, str, Any]:
    """``"node.param=value"`` -> ``(node, param, value)``, the value parsed as JSON when it parses."""
    key, sep, raw = text.partition("=")
    node, dot, param = key.strip().rpartition(".")
    if not (sep and dot and node and param):
        raise ParameterError(f"--set {text!r}: expected NODE.PARAM=VALUE, e.g. --set design.samples=32")
    try:
        value = json.loads(raw)
    except json.JSONDecodeError:
        value = raw
    return node, param, value


def _hint(name: str, known: Iterable[str]) -> str:
    close = difflib.get_close_matches(name, list(known), n=3)
    return f" (did you mean {' or '.join(close)}?)" if close else ""


def apply_overrides(pipeline: Pipeline, assignments: Iterable[str]) -> list[Override]:
    """Set each ``node.param=value`` of ``assignments`` on ``pipeline`` after validating it; return what was set."""
    registry = get_registry()
    applied = []
    for text in assignments:
        name, param, value = parse_override(text)
        if name not in pipeline.nodes:
            nodes = ", ".join(f"{n} ({node.stage})" for n, node in pipeline.nodes.items())
            raise PipelineError(f"--set {text}: pipeline {pipeline.name!r} has no node {name!r}"
                                f"{_hint(name, pipeline.nodes)}; its nodes (stage): {nodes}")
        node = pipeline.nodes[name]
        if node.stage == "data":
            raise PipelineError(f"--set {text}: node {name!r} holds a dataset and has no parameters")
        stage = registry.stage(node.stage)
        if param not in stage.params:
            known = "; ".join(f"{p} ({spec.kind.__name__}, {spec.describe_range()})"
                              for p, spec in sorted(stage.params.items())) or "none"
            raise ParameterError(f"--set {text}: stage {stage.name!r} of node {name!r} has no parameter {param!r}"
                                 f"{_hint(param, stage.params)}; its parameters: {known}")
        try:
            checked = validate_params(stage.name, {param: stage.params[param]}, {param: value})[param]
        except ParameterError as exc:
            raise ParameterError(f"--set {text} (node {name!r}): {exc}") from None
        spec = stage.params[param]
        if param in node.params:
            replaced = json.dumps(node.params[param], default=str)
        elif spec.required:
            replaced = "no value (required)"
        else:
            replaced = f"the stage default {json.dumps(spec.default, default=str)}"
        pipeline.set_params(name, **{param: checked})
        applied.append(Override(name, param, checked, replaced))
    return applied
