"""One coreflood of a study (:class:`Experiment`): its role, data file, core, rate, schedule, fluids and measurement
chain, resolved and validated (:mod:`spflow.study.study_file`), in the forward model's units."""

from __future__ import annotations

import hashlib
import json
from dataclasses import asdict, dataclass, field
from pathlib import Path

import xarray as xr

from spflow.io.format import schedule_json
from spflow.io.metadata import CORE_ATTRS, core_unit
from spflow.plugins.forward.schedule import Schedule
from spflow.synthetic.core_volumes import ooip_ml, pore_volume_ml
from spflow.synthetic.noise_model import NoiseModel

from .errors import StudyError

__all__ = ["Experiment"]


@dataclass(frozen=True)
class Experiment:
    """A study's coreflood.

    Attributes:
        name: the experiment's name (unique in the study; the ``experiment`` attr of its observations).
        role: ``"calibration"``, ``"heldout"`` or ``"predict"``.
        data: absolute path of the data file (``None`` for a predict-only experiment without data).
        core: core attrs of :mod:`spflow.io.metadata` (``core_length_m`` ... ``qinj_ml_min``), format units.
        schedule: the injection schedule.
        fluids: forward-model fluid parameters the study gives for this experiment (``VIS2`` ...), model units.
        measurement: the measurement chain.
        sources: ``{field: "study" | "data" | "study and data" | "default"}`` for every resolved field.
    """

    name: str
    role: str
    data: Path | None
    core: dict[str, float]
    schedule: Schedule
    fluids: dict[str, float]
    measurement: NoiseModel
    sources: dict[str, str]
    dataset: xr.Dataset | None = field(repr=False, compare=False)

    def model_params(self) -> dict[str, float]:
        """Forward-model overrides of this experiment: ``LENGTH``, ``DIAMETER``, ``PORO``, ``PERM``, ``SWI``,
        ``QINJ`` and the fluids it gives (forward-model units)."""
        return {CORE_ATTRS[attr]: value for attr, value in self.core.items()} | dict(self.fluids)

    def noise_model(self) -> NoiseModel:
        """The measurement chain (:class:`~spflow.synthetic.NoiseModel`)."""
        return self.measurement

    def pore_volume_ml(self) -> float:
        """Pore volume ``pi D^2 / 4 L phi`` (ml)."""
        return pore_volume_ml(self.model_params())

    def observed_attrs(self) -> dict:
        """The metadata the study resolved for the data file (JSON-able): ``experiment`` = the study name, the core
        attrs with units, ``pore_volume_ml``/``ooip_ml`` (from the core where the file has none), the schedule JSON,
        the measurement chain ``noise_*`` and ``study_role``; they override the file's own attrs."""
        own = {} if self.dataset is None else self.dataset.attrs
        params = self.model_params()
        attrs: dict = {}
        if "pore_volume_ml" not in own:
            attrs["pore_volume_ml"] = pore_volume_ml(params)
        if "ooip_ml" not in own:
            attrs["ooip_ml"] = ooip_ml(params)
        for attr, value in self.core.items():
            attrs.update({attr: value, f"{attr}_units": core_unit(attr)})
        attrs.update(self.measurement.to_attrs())
        attrs.update(experiment=self.name, schedule=schedule_json(self.schedule), study_role=self.role)
        return attrs

    def observations(self) -> xr.Dataset:
        """The coreflood Dataset (:func:`spflow.io.load_coreflood` format) with :meth:`observed_attrs` as attrs.
        A predict-only experiment without data raises :class:`StudyError`."""
        if self.dataset is None:
            raise StudyError(f"experiment {self.name!r} ({self.role}) has no data file: nothing was observed")
        ds = self.dataset.copy()
        ds.attrs = dict(ds.attrs) | self.observed_attrs()
        return ds

    def observation_source(self) -> dict:
        """The ``observations`` / ``diagnose`` stages' description of this experiment's data: ``{"name", "data",
        "sha256", "attrs"}`` (:func:`spflow.io.observed_source.load_observed`); the digest and the resolved attrs
        make the stages' provenance keys see an edited data file or study. A predict-only experiment without data
        raises :class:`StudyError`."""
        if self.data is None:
            raise StudyError(f"experiment {self.name!r} ({self.role}) has no data file: nothing was observed")
        attrs = {k: v.item() if hasattr(v, "item") else v for k, v in self.observed_attrs().items()}
        return {"name": self.name, "data": str(self.data), "sha256": self.data_digest(), "attrs": attrs}

    def data_digest(self) -> str | None:
        """SHA-256 of the data file's bytes (so caching keys see a changed file); ``None`` without data."""
        return None if self.data is None else hashlib.sha256(self.data.read_bytes()).hexdigest()

    def forward_experiment(self) -> dict:
        """The ``forward`` stage's description of this experiment: ``{"name", "schedule", "params"}``."""
        return {"name": self.name, "schedule": json.loads(schedule_json(self.schedule)),
                "params": self.model_params()}

    def to_dict(self) -> dict:
        """JSON-able content (data file path and digest, every resolved value and its source)."""
        return {"name": self.name, "role": self.role, "data": None if self.data is None else str(self.data),
                "data_sha256": self.data_digest(),
                "core": {attr: {"value": v, "units": core_unit(attr)} for attr, v in self.core.items()},
                "schedule": json.loads(schedule_json(self.schedule)), "fluids": dict(self.fluids),
                "measurement": asdict(self.measurement), "sources": dict(self.sources)}
