"""Where a diagnosis spends its forward runs and its time: a ledger per phase (issue 20, item 5).

:func:`~spflow.plugins.gap.diagnosis.diagnose` switches the ledger as it moves from one phase to the next; the
:class:`~spflow.plugins.gap.prediction.Predictor` charges every new (not memoised) forward run to the current
phase, with the CPU seconds they took in the processes that ran them. The result, ``{phase: Cost}`` (forward runs,
their CPU seconds, CPU seconds of the diagnosing process itself, wall seconds), is kept in the diagnosis
(``GapDiagnosis.cost``) and printed by ``benchmarks/bench_diagnosis.py``.
"""

from __future__ import annotations

import time
from typing import NamedTuple

from .prediction import Predictor

__all__ = ["PHASES", "Cost", "CostLedger"]

#: the phases, in the order a diagnosis first enters them
PHASES = ("base calibration", "numerical error", "scores", "screening", "refits", "subsets", "final fit", "views")


class Cost(NamedTuple):
    """The cost of one phase."""

    runs: int          #: new forward runs
    run_cpu_s: float   #: their CPU seconds (in the processes that ran them: joblib workers or this one)
    own_cpu_s: float   #: CPU seconds of the diagnosing process (the runs made in it included)
    wall_s: float      #: wall seconds


class CostLedger:
    """Forward runs, CPU and wall time per phase of one diagnosis on ``predictor``."""

    def __init__(self, predictor: Predictor):
        self.predictor = predictor
        self.seconds: dict[str, float] = {}
        self.cpu: dict[str, float] = {}
        self.extra: dict[str, tuple[int, float]] = {}
        self._phase: str | None = None
        self._since, self._since_cpu = time.perf_counter(), time.process_time()

    def enter(self, phase: str) -> str | None:
        """Charge the time since the last switch to the current phase, make ``phase`` current; returns the phase
        left (to return to it after a nested one)."""
        if phase not in PHASES:
            raise ValueError(f"unknown diagnosis phase {phase!r}; allowed {list(PHASES)}")
        now, now_cpu, left = time.perf_counter(), time.process_time(), self._phase
        if left is not None:
            self.seconds[left] = self.seconds.get(left, 0.0) + now - self._since
            self.cpu[left] = self.cpu.get(left, 0.0) + now_cpu - self._since_cpu
        self._phase, self._since, self._since_cpu = phase, now, now_cpu
        self.predictor.phase = phase
        return left

    def add_runs(self, phase: str, runs: int, cpu_s: float) -> None:
        """Charge ``runs`` forward runs made outside the predictor (other numerics) and their CPU seconds to
        ``phase``."""
        n, c = self.extra.get(phase, (0, 0.0))
        self.extra[phase] = (n + runs, c + cpu_s)

    def table(self) -> dict[str, Cost]:
        """``{phase: Cost}`` of every phase entered so far (the current one up to now), in the order of
        :data:`PHASES`."""
        if self._phase is not None:
            self.enter(self._phase)
        runs, cpu = self.predictor.runs_by_phase, self.predictor.run_cpu_by_phase
        return {p: Cost(runs.get(p, 0) + self.extra.get(p, (0, 0.0))[0],
                        cpu.get(p, 0.0) + self.extra.get(p, (0, 0.0))[1], self.cpu.get(p, 0.0),
                        self.seconds.get(p, 0.0))
                for p in PHASES if p in self.seconds or p in runs or p in self.extra}
