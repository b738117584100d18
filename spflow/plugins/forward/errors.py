"""The forward model's runtime failure: raised when the compiled kernel reports a failed step."""

from __future__ import annotations

from spflow.core.errors import SpflowError

from . import state_layout as L

__all__ = ["SimulationError"]

_REASONS = {
    L.ERR_COLLAPSE: "time-step collapse (a component would turn negative even after 60 step halvings)",
    L.ERR_NONFINITE: "non-finite or empty state",
    L.ERR_IMMOBILE: "no mobile phase (total mobility is zero)",
    L.ERR_STEPS: "step budget exhausted (the cell is the one limiting the time step)",
    L.ERR_WALL: "wall-time budget exhausted (the cell is the one limiting the time step)",
}
_STATE_NAMES = ("water", "oil", "surfactant", "polymer", "anions", "divalent", "S_aqueous", "S_oleic", "S_me")


class SimulationError(SpflowError, RuntimeError):
    """A forward run failed; ``pv`` (injected PV), ``cell`` (0-based), ``state`` (dict) and ``code`` say where;
    ``reason`` is the failure in words (with the exhausted ``budget``, e.g. ``"max_steps = 100"``, if one was)."""

    def __init__(self, code: int, info, cells: int, budget: str | None = None):
        self._args = (code, [float(v) for v in info], cells, budget)
        self.code = int(code)
        self.pv = float(info[0])
        self.cell = int(info[1])
        self.state = {name: float(v) for name, v in zip(_STATE_NAMES, info[2:11])}
        self.dt = float(info[11])
        self.reason = _REASONS.get(self.code, "unknown failure") + (f" [{budget}]" if budget else "")
        state = ", ".join(f"{k}={v:.6g}" for k, v in self.state.items())
        super().__init__(
            f"forward simulation failed at {self.pv:.6g} PV in cell {self.cell} of {cells} "
            f"(x/L = {(self.cell + 0.5) / cells:.4g}): {self.reason}; "
            f"cell state (PV units, saturations): {state}; time step {self.dt:.3g} PV"
        )

    def __reduce__(self):
        """Pickle by the constructor's arguments (a run failing in a joblib worker reaches the caller intact)."""
        return type(self), self._args
