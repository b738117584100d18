"""Provenance keys (Merkle-style) and the explanation of why a node is stale.

key(node) = H(stage name, stage version, code fingerprint, providing distribution's version, canonical params,
external-data fingerprint, {port: key(upstream)}). Keys depend only on declarations and upstream keys, so the whole
pipeline's keys are known before anything runs, and an upstream key doubles as the version of its data.
"""

from __future__ import annotations

import importlib.metadata
from functools import lru_cache
from typing import Any

from .hashing import canonical_hash
from .stage import Stage

__all__ = ["provenance", "key_of", "stale_reasons"]


@lru_cache(maxsize=None)
def _distributions() -> dict[str, list[str]]:
    """Top-level module -> distributions (scanning every installed package's files: ~0.4 s, so once per process)."""
    return importlib.metadata.packages_distributions()


@lru_cache(maxsize=None)
def _distribution_version(module: str) -> str:
    top = module.split(".")[0]
    for dist in _distributions().get(top, []):
        try:
            return f"{dist}=={importlib.metadata.version(dist)}"
        except importlib.metadata.PackageNotFoundError:
            continue
    return "unpackaged"


def provenance(stage: Stage, input_keys: dict[str, str]) -> dict[str, Any]:
    """The components of a node's key (stored in the manifest so that ``status`` can say what changed)."""
    cls = type(stage)
    return {
        "stage": cls.name,
        "version": cls.version,
        "code": cls.code_fingerprint(),
        "distribution": _distribution_version(cls.__module__),
        "params": dict(stage.params),
        "fingerprint": stage.fingerprint(),
        "inputs": dict(sorted(input_keys.items())),
    }


def key_of(prov: dict[str, Any]) -> str:
    return canonical_hash(prov)


def _diff_params(old: dict[str, Any], new: dict[str, Any]) -> str:
    names = sorted(set(old) | set(new))
    parts = [f"{n}: {old.get(n, '<unset>')!r} -> {new.get(n, '<unset>')!r}" for n in names if old.get(n) != new.get(n)]
    return ", ".join(parts)


def stale_reasons(old: dict[str, Any] | None, new: dict[str, Any], upstream_nodes: dict[str, str]) -> list[str]:
    """Human-readable causes (code/version, params, upstream data) for a node whose key is not in the store."""
    if not old:
        return ["never run"]
    reasons = []
    if old.get("stage") != new["stage"]:
        reasons.append(f"stage swapped: {old.get('stage')} -> {new['stage']}")
    else:
        code = [f"{k} {old.get(k)} -> {new[k]}" for k in ("version", "code", "distribution") if old.get(k) != new[k]]
        if code:
            reasons.append("code/version changed: " + "; ".join(code))
        if old.get("params") != new["params"]:
            reasons.append("params changed: " + _diff_params(old.get("params", {}), new["params"]))
    if old.get("fingerprint") != new["fingerprint"]:
        reasons.append("external data changed")
    changed = [p for p in new["inputs"] if old.get("inputs", {}).get(p) != new["inputs"][p]]
    if changed:
        reasons.append("upstream data changed: " + ", ".join(f"{p} (from {upstream_nodes[p]!r})" for p in changed))
    return reasons or ["result missing from the cache"]
