"""Fixtures-as-functions shared by the framework tests."""

from __future__ import annotations

import contextlib
from collections.abc import Iterator

import spflow
import toy_stages


@contextlib.contextmanager
def toy_plugin() -> Iterator[None]:
    spflow.register_plugin(toy_stages, name="toy_stages")
    try:
        yield
    finally:
        spflow.unregister_plugin("toy_stages")


def chain(log: str, value: float = 1.0, factor: float = 2.0, delay: float = 0.0) -> spflow.Pipeline:
    """a (source) -> b (scale) -> c (scale); d (source) independent; e = add(c, d). Sources and scales sleep
    ``delay`` seconds."""
    slow = {"delay": delay} if delay else {}
    p = spflow.Pipeline("chain")
    p.add("a", "toy_source", params={"value": value, "log": log, **slow})
    p.add("b", "toy_scale", inputs={"data": "a"}, params={"factor": factor, "log": log, **slow})
    p.add("c", "toy_scale", inputs={"data": "b"}, params={"factor": 3.0, "log": log, **slow})
    p.add("d", "toy_source", params={"value": 5.0, "log": log, **slow})
    p.add("e", "toy_add", inputs={"a": "c", "b": "d"}, params={"log": log})
    return p
