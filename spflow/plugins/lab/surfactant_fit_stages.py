"""Stages fitting the surfactant support experiments of thesis chapter 2: phase behaviour (Fig. 2.5), IFT (Fig. 2.6),
microemulsion viscosity (Fig. 2.7) and capillary desaturation (Fig. 2.8).

Each stage reads one lab table (parameter ``path``; empty = the bundled synthetic test
``spflow/datasets/lab/<kind>.csv``, truth in ``surfactant_truth.toml``), fits the forward model's own sub-model to it and
returns the FIT dataset (:data:`spflow.plugins.lab.fit_result.FIT`) with the data and the fitted curve as extra
variables. The table is read and validated when the provenance key is computed -- before any stage runs -- and the
key follows the file's bytes, not its path or modification time.
"""

from __future__ import annotations

import hashlib
from collections.abc import Callable
from pathlib import Path
from typing import ClassVar

import xarray as xr

from spflow.core.errors import ParameterError
from spflow.core.params import Param
from spflow.core.stage import Stage, StageContext
from spflow.plugins.lab import desaturation_fit, ift_fit, me_viscosity_fit, phase_behaviour_fit
from spflow.plugins.lab.fit_result import FIT
from spflow.plugins.lab.polymer_fit_stages import bundled_lab_path

__all__ = ["FitPhaseBehaviour", "FitIFT", "FitMEViscosity", "FitDesaturation"]


class _LabTableFit(Stage):
    """A stage fitting one lab table: subclasses set ``kind``, ``read`` (path -> Dataset) and ``fit``."""

    version = "3"  # 3: units in UDUNITS form (meq/ml written mmol/ml), issue 23
    kind: ClassVar[str] = ""
    output = FIT
    read: ClassVar[Callable[[Path], xr.Dataset]]
    params = {"path": Param(str, "", doc="lab table (CSV); empty = the bundled synthetic test of this kind")}

    def __init__(self, **params):
        super().__init__(**params)
        path = self.path
        if not path.is_file():
            raise ParameterError(f"stage {self.name!r} parameter 'path': no such lab table {str(path)!r}")

    @property
    def path(self) -> Path:
        return Path(self.params["path"]) if self.params["path"] else bundled_lab_path(self.kind)

    def _data(self) -> xr.Dataset:
        """The parsed table, read and validated once per stage instance."""
        if getattr(self, "_table", None) is None:
            self._table = type(self).read(self.path)
        return self._table

    def fingerprint(self) -> str:
        self._data()
        return hashlib.sha256(self.path.read_bytes()).hexdigest()

    def fit(self, data: xr.Dataset) -> xr.Dataset:  # pragma: no cover - abstract
        raise NotImplementedError

    def run(self, ctx: StageContext) -> xr.Dataset:
        return self.fit(self._data())


class FitPhaseBehaviour(_LabTableFit):
    name = "fit_phase_behaviour"
    description = "fit Hand's rule (CSEL, CSEU, HBNC70-72) to pipette solubilization ratios vs salinity (Fig. 2.5)"
    kind = phase_behaviour_fit.KIND
    read = staticmethod(phase_behaviour_fit.read_pipette_tests)

    def fit(self, data):
        return phase_behaviour_fit.fit_phase_behaviour(data)


class FitIFT(_LabTableFit):
    name = "fit_ift"
    description = "fit the Chun-Huh IFT law (CHUH, AHUH) to IFT vs solubilization ratio (Eqs. 2.9-2.10, Fig. 2.6)"
    kind = ift_fit.KIND
    read = staticmethod(ift_fit.read_ift_table)

    def fit(self, data):
        return ift_fit.fit_ift(data)


class FitMEViscosity(_LabTableFit):
    name = "fit_me_viscosity"
    description = "fit the microemulsion viscosity law (ALPHAV1-5) to viscosity vs composition (Eq. 2.11, Fig. 2.7)"
    kind = me_viscosity_fit.KIND
    read = staticmethod(me_viscosity_fit.read_me_viscosity_table)
    params = {
        **_LabTableFit.params,
        "fit": Param(list, ["ALPHAV1", "ALPHAV2"], choices=me_viscosity_fit.NAMES,
                     doc="ALPHAVs to estimate; the others stay at their forward-model defaults (Table 2.4)"),
    }

    def fit(self, data):
        return me_viscosity_fit.fit_me_viscosity(data, fit=tuple(self.params["fit"]))


class FitDesaturation(_LabTableFit):
    name = "fit_desaturation"
    description = "fit the capillary desaturation curve (T_ll, S_lRWC, S_lRC) to residual saturation vs N_c (Eq. 2.12)"
    kind = desaturation_fit.KIND
    read = staticmethod(desaturation_fit.read_desaturation_table)

    def fit(self, data):
        return desaturation_fit.fit_desaturation(data)
