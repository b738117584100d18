"""Sub-model groups of a screening (Algorithm 1's loop over the models M_1..M_t) and the runs they need.

``mode = "per_group"`` screens each group alone: its parameters vary over their box while every other parameter of
the space stays at its default (the thesis's per-model analysis of Fig. 3.2). ``mode = "joint"`` varies all
parameters together in one design; the group labels then only organise the output and the per-group top-k rule.
Either way, every run is a full row over the space, so one ``forward`` call covers all groups and parallelises
over every run at once.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from spflow.core.errors import ParameterError

__all__ = ["JOINT", "resolve_groups", "ScreeningBlock", "blocks_for", "full_design"]

#: Group label used when no groups are given.
JOINT = "all"


def resolve_groups(stage: str, names: list[str], groups: Mapping[str, list]) -> dict[str, list[str]]:
    """Check that ``groups`` partitions the space's parameter ``names``; empty ``groups`` is one group of all.

    Groups keep the order of their first parameter in the space, parameters their order in the space.
    """
    if not groups:
        return {JOINT: list(names)}
    seen: dict[str, str] = {}
    for label, members in groups.items():
        if not isinstance(members, (list, tuple)) or not members:
            raise ParameterError(f"stage {stage!r} parameter 'groups': group {label!r} must be a non-empty list of "
                                 f"parameter names, got {members!r}")
        for name in members:
            if name not in names:
                raise ParameterError(f"stage {stage!r} parameter 'groups': {name!r} (group {label!r}) is not in the "
                                     f"input space; space parameters: {list(names)}")
            if name in seen:
                raise ParameterError(f"stage {stage!r} parameter 'groups': {name!r} is in groups {seen[name]!r} and "
                                     f"{label!r}; each parameter belongs to one group")
            seen[name] = label
    missing = [n for n in names if n not in seen]
    if missing:
        raise ParameterError(f"stage {stage!r} parameter 'groups': space parameters {missing} are in no group; "
                             "list every parameter of the space (or leave 'groups' empty)")
    order = sorted(groups, key=lambda g: min(names.index(n) for n in groups[g]))
    return {g: [n for n in names if seen[n] == g] for g in order}


@dataclass(frozen=True)
class ScreeningBlock:
    """One screening design: the parameters varied together (``columns`` into the space) and their run rows."""

    names: list[str]
    columns: np.ndarray
    rows: slice


def blocks_for(names: list[str], groups: dict[str, list[str]], mode: str, runs) -> list[ScreeningBlock]:
    """The designs of a screening: one per group (``per_group``) or one over the whole space (``joint``).

    ``runs(d)`` is the number of model runs of a d-parameter design; the blocks' rows follow each other.
    """
    sets = list(groups.values()) if mode == "per_group" else [list(names)]
    blocks, start = [], 0
    for members in sets:
        n = runs(len(members))
        blocks.append(ScreeningBlock(members, np.array([names.index(m) for m in members]), slice(start, start + n)))
        start += n
    return blocks


def full_design(default: np.ndarray, blocks: list[ScreeningBlock], samples: list[np.ndarray]) -> np.ndarray:
    """Rows over the whole space: each block's sample in its columns, the space's defaults elsewhere."""
    total = blocks[-1].rows.stop
    x = np.tile(np.asarray(default, dtype=float), (total, 1))
    for block, sample in zip(blocks, samples):
        x[block.rows, block.columns] = sample
    return x
