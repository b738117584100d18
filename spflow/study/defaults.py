"""A default a study took (:class:`DefaultTaken`): the record that makes every assumption visible."""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["DefaultTaken"]


@dataclass(frozen=True)
class DefaultTaken:
    """One value a study did not give and the data file did not hold, filled with the documented default.

    ``experiment`` is ``None`` for study-wide fields (``effects``); ``field`` is the study key (``measurement.
    dead_volume_ml``, ``fluids.VIS2``); ``value`` the default with units; ``why`` where the default comes from.
    """

    experiment: str | None
    field: str
    value: str
    why: str

    def describe(self) -> str:
        """One line: ``experiment 'x': measurement.tube_pv = 0.05 PV (why)``."""
        where = "study" if self.experiment is None else f"experiment {self.experiment!r}"
        return f"{where}: {self.field} = {self.value} ({self.why})"

    def to_dict(self) -> dict:
        return {"experiment": self.experiment, "field": self.field, "value": self.value, "why": self.why}
