"""The cost ledger of a diagnosis: forward runs and their CPU time charged to the phase that was current when they
ran, wall and own CPU time to the phase that was current while it passed (a stand-in predictor and clocks), other
numerics' runs added."""

import pytest

from spflow.plugins.gap import cost
from spflow.plugins.gap.cost import CostLedger


class StubPredictor:
    """Charges ``n`` runs of 0.25 CPU s each to its current phase, like Predictor.predict does for new runs."""

    def __init__(self):
        self.phase, self.runs_by_phase, self.run_cpu_by_phase = "other", {}, {}

    def run(self, n):
        self.runs_by_phase[self.phase] = self.runs_by_phase.get(self.phase, 0) + n
        self.run_cpu_by_phase[self.phase] = self.run_cpu_by_phase.get(self.phase, 0.0) + 0.25 * n


def test_runs_and_time_per_phase(monkeypatch):
    clock = iter([0.0, 1.0, 4.0, 4.5, 10.0, 12.0])
    cpu = iter([0.0, 0.5, 1.0, 1.25, 2.0, 3.0])   # the diagnosing process's own CPU clock
    monkeypatch.setattr(cost.time, "perf_counter", lambda: next(clock))
    monkeypatch.setattr(cost.time, "process_time", lambda: next(cpu))
    predictor = StubPredictor()
    ledger = CostLedger(predictor)              # t = 0
    ledger.enter("base calibration")            # t = 1
    predictor.run(30)
    left = ledger.enter("scores")               # t = 4: 3 s of base calibration
    assert left == "base calibration" and predictor.phase == "scores"
    predictor.run(11)
    ledger.enter(left)                          # t = 4.5: 0.5 s of scores
    predictor.run(5)
    ledger.add_runs("numerical error", 6, 4.0)  # runs on other numerics, no time of their own here
    ledger.enter("refits")                      # t = 10: 5.5 s more of base calibration
    predictor.run(100)
    table = ledger.table()                      # t = 12: 2 s of refits so far
    # (runs, their CPU s, own CPU s, wall s)
    assert table == {"base calibration": (35, 35 * 0.25, 0.5 + 0.75, 3.0 + 5.5), "numerical error": (6, 4.0, 0, 0),
                     "scores": (11, 11 * 0.25, 0.25, 0.5), "refits": (100, 25.0, 1.0, 2.0)}
    assert table["refits"].run_cpu_s == 25.0 and table["scores"].wall_s == 0.5
    assert list(table) == [p for p in cost.PHASES if p in table]   # in the order a diagnosis enters them


def test_unknown_phase_is_refused():
    with pytest.raises(ValueError, match="unknown diagnosis phase 'fitting'"):
        CostLedger(StubPredictor()).enter("fitting")
