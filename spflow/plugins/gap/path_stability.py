"""How a diagnosis's verdict holds when the optimiser takes another path (docs/gap.md, Cost: "the diagnosis's own
sensitivity to the optimiser path").

Every fit of a diagnosis (base calibration, candidate refits, joint subsets) is a budgeted least-squares run with
forward-difference Jacobians; on a base model that the calibration corefloods do not pin down, the refits end in
flat valleys or among local optima, and the held-out scores that decide the verdict can differ between those end
points by more than their standard errors. In the twin study a 10 % larger difference step changed 3 of 14
verdicts and 4 of 14 ambiguity sets, although a rerun with the same options reproduces every record exactly.

With ``path_reruns = n`` the whole diagnosis is rerun ``n`` times with the relative difference step scaled by
:func:`step_factors` (1.1, 0.9, 1.2, 0.8, 1.3: each rerun a different, equally valid optimiser path) and
everything else unchanged. A rerun *agrees* when its verdict, its ambiguity set and its declared effects are the
main run's; the report lists every rerun (difference step, verdict, set, effects with strengths, forward runs) and
whether it agrees. A verdict that changes under a perturbed path is not a finding of the data but of the path:
read it as uncertain between the verdicts listed. Each rerun costs about one diagnosis.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import asdict, dataclass

__all__ = ["PathRerun", "MAX_RERUNS", "step_factors", "rerun_paths"]

#: the most reruns a diagnosis takes (the ``path_reruns`` stage parameter's upper bound)
MAX_RERUNS = 5


@dataclass(frozen=True)
class PathRerun:
    """One rerun of a diagnosis along another optimiser path, and whether it agrees with the main run."""

    diff_step: float
    verdict: str
    ambiguity_set: list[str]
    effects: dict[str, float]
    forward_runs: int
    agrees: bool

    def as_dict(self) -> dict:
        return asdict(self)


def step_factors(count: int) -> list[float]:
    """The scale factors of the difference step of ``count`` reruns: 1.1, 0.9, 1.2, 0.8, 1.3 (alternating, in
    tenths)."""
    if not 0 <= count <= MAX_RERUNS:
        raise ValueError(f"path reruns must be 0..{MAX_RERUNS}, got {count}")
    return [1.0 + 0.1 * ((k + 2) // 2) * (1 if k % 2 == 0 else -1) for k in range(count)]


def rerun_paths(rerun: Callable[[float], tuple[str, list[str], dict[str, float], int]], diff_step: float,
                count: int, verdict: str, ambiguity: list[str], effects: dict[str, float]) -> list[PathRerun]:
    """``count`` reruns: ``rerun(step)`` diagnoses with the difference step ``step`` and returns (verdict,
    ambiguity set, declared effects with strengths, forward runs); each is compared with the main run's
    ``verdict``, ``ambiguity`` and ``effects`` (names; strengths are reported, not compared)."""
    out = []
    for factor in step_factors(count):
        step = float(f"{diff_step * factor:.12g}")  # 0.011, not 0.011000000000000001
        v, s, e, runs = rerun(step)
        out.append(PathRerun(step, v, list(s), dict(e), runs,
                             v == verdict and set(s) == set(ambiguity) and set(e) == set(effects)))
    return out
