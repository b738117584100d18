"""The screening selection rule (Algorithm 1, step 8: "get the reduced input vector"): which parameters to keep.

Each parameter gets a score in [0, 1]-ish (the stage decides: the largest total Sobol index S_i^T of Eq. 3.3 over
the selection QoIs, or Morris's normalised mu*). A parameter is kept when

* ``combine = "and"``: its score is >= ``threshold`` **and** (if ``top_k`` > 0) it ranks among the ``top_k`` best;
* ``combine = "or"``: its score is >= ``threshold`` **or** (if ``top_k`` > 0) it ranks among the ``top_k`` best,

where ranks are counted within each group (sub-model, ``top_k_scope = "group"``, as the thesis keeps the most
sensitive parameters of every model) or over all parameters (``"all"``). ``threshold = 0`` with ``combine = "and"``
is a pure top-k rule; ``top_k = 0`` a pure threshold rule; ``combine = "or"`` with ``top_k = 1`` keeps at least one
parameter per sub-model.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from spflow.core.params import Param

__all__ = ["SelectionRule", "SELECTION_PARAMS"]

#: Stage parameters of the rule (shared by every screening stage).
SELECTION_PARAMS = {
    "threshold": Param(float, 0.1, bounds=(0.0, 1.0), doc="keep parameters whose score is >= threshold"),
    "top_k": Param(int, 0, bounds=(0, 10_000), doc="keep the top_k scores per scope (0: no rank rule)"),
    "combine": Param(str, "and", choices=["and", "or"], doc="how the threshold and top-k rules combine"),
    "top_k_scope": Param(str, "group", choices=["group", "all"], doc="rank within each group or over all"),
}


@dataclass(frozen=True)
class SelectionRule:
    """Threshold and/or top-k selection (module docstring)."""

    threshold: float = 0.1
    top_k: int = 0
    combine: str = "and"
    top_k_scope: str = "group"

    @classmethod
    def from_params(cls, params: Mapping) -> SelectionRule:
        return cls(*(params[name] for name in SELECTION_PARAMS))

    def apply(self, score: np.ndarray, group: np.ndarray) -> np.ndarray:
        """Boolean mask over parameters; ``score`` and ``group`` labels are arrays of the same length."""
        score = np.asarray(score, dtype=float)
        group = np.asarray(group)
        above = score >= self.threshold
        if self.top_k == 0:
            return above
        ranked = np.zeros(score.size, dtype=bool)
        scopes = [np.arange(score.size)] if self.top_k_scope == "all" else [
            np.flatnonzero(group == g) for g in dict.fromkeys(group.tolist())]
        for members in scopes:
            best = members[np.argsort(-score[members], kind="stable")[: self.top_k]]
            ranked[best] = True
        return above & ranked if self.combine == "and" else above | ranked

    def describe(self) -> str:
        text = f"score >= {self.threshold:g}"
        if self.top_k:
            text += f" {self.combine} among the top {self.top_k} per {self.top_k_scope}"
        return text
