"""Where a diagnosis spends its forward runs and its time: a ledger per phase (issue 20, item 5).

:func:`~spflow.plugins.gap.diagnosis.diagnose` switches the ledger as it moves from one phase to the next; the
:class:`~spflow.plugins.gap.prediction.Predictor` charges every new (not memoised) forward run to the current
phase. The result, ``{phase: (forward runs, wall seconds)}``, is kept in the diagnosis
(``GapDiagnosis.cost``) and printed by ``benchmarks/bench_diagnosis.py``.
"""

from __future__ import annotations

import time

from .prediction import Predictor

__all__ = ["PHASES", "CostLedger"]

#: the phases, in the order a diagnosis first enters them
PHASES = ("base calibration", "numerical error", "scores", "screening", "refits", "subsets", "views")


class CostLedger:
    """Forward runs and wall time per phase of one diagnosis on ``predictor``."""

    def __init__(self, predictor: Predictor):
        self.predictor = predictor
        self.seconds: dict[str, float] = {}
        self.extra_runs: dict[str, int] = {}
        self._phase: str | None = None
        self._since = time.perf_counter()

    def enter(self, phase: str) -> str | None:
        """Charge the time since the last switch to the current phase, make ``phase`` current; returns the phase
        left (to return to it after a nested one)."""
        if phase not in PHASES:
            raise ValueError(f"unknown diagnosis phase {phase!r}; allowed {list(PHASES)}")
        now, left = time.perf_counter(), self._phase
        if left is not None:
            self.seconds[left] = self.seconds.get(left, 0.0) + now - self._since
        self._phase, self._since = phase, now
        self.predictor.phase = phase
        return left

    def add_runs(self, phase: str, runs: int) -> None:
        """Charge ``runs`` forward runs made outside the predictor (other numerics) to ``phase``."""
        self.extra_runs[phase] = self.extra_runs.get(phase, 0) + runs

    def table(self) -> dict[str, tuple[int, float]]:
        """``{phase: (forward runs, wall seconds)}`` of every phase entered so far (the current one up to now)."""
        if self._phase is not None:
            self.enter(self._phase)
        runs = self.predictor.runs_by_phase
        return {p: (runs.get(p, 0) + self.extra_runs.get(p, 0), self.seconds.get(p, 0.0))
                for p in PHASES if p in self.seconds or p in runs or p in self.extra_runs}
