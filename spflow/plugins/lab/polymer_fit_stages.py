"""Lab-fit stages for polymer rheology, the single-phase polymer coreflood, adsorption and the tracer test.

Each stage reads its lab table(s) (param ``path``; empty = the bundled synthetic file in ``spflow/datasets/lab``),
fits its sub-model and returns a FIT dataset (:data:`.fit_result.FIT`) plus the data and fitted curves for the
figures of :mod:`.polymer_fit_figures`. The cache key follows the files' content (``fingerprint``), not their path.
"""

from __future__ import annotations

import hashlib
from pathlib import Path

import xarray as xr

import spflow.datasets
from spflow.core.errors import ParameterError
from spflow.core.params import Param
from spflow.core.stage import Stage, StageContext

from . import adsorption_fit, polymer_coreflood, polymer_rheology, tracer_fit
from .fit_result import FIT
from .lab_table import read_lab_table

__all__ = ["bundled_lab_path", "FitPolymerRheology", "FitPolymerCoreflood", "FitAdsorption", "FitTracer"]

LAB_DIR = Path(spflow.datasets.__file__).resolve().parent / "lab"


def bundled_lab_path(kind: str) -> Path:
    """Path of the bundled synthetic lab table of ``kind`` (``spflow/datasets/lab/<kind>.csv``)."""
    return LAB_DIR / f"{kind}.csv"


def _resolve(stage: str, param: str, value: str, kind: str) -> Path:
    path = Path(value) if value else bundled_lab_path(kind)
    if not path.is_file():
        raise ParameterError(f"stage {stage!r} parameter {param!r}: no such file {str(path)!r}")
    return path


def _content_hash(*paths: Path) -> str:
    digest = hashlib.sha256()
    for p in paths:
        digest.update(p.read_bytes())
    return digest.hexdigest()


_PATH_DOC = "lab table (CSV, spflow lab-table format); empty = the bundled synthetic data"


class FitPolymerRheology(Stage):
    name = "fit_polymer_rheology"
    version = "3"  # 3: units in UDUNITS form (meq/ml written mmol/ml), issue 23
    description = "fit AP1-3, SSLOPE, BETAP, POWN and Eq. 2.5 A0-A2 to polymer shear sweeps (Eqs. 2.1-2.5)"
    output = FIT
    params = {"path": Param(str, "", doc=_PATH_DOC)}

    def _path(self) -> Path:
        return _resolve(self.name, "path", self.params["path"], polymer_rheology.KIND)

    def fingerprint(self) -> str:
        return _content_hash(self._path())

    def run(self, ctx: StageContext) -> xr.Dataset:
        data = read_lab_table(self._path(), polymer_rheology.KIND, polymer_rheology.COLUMNS)
        return polymer_rheology.fit_rheology(data)


class FitPolymerCoreflood(Stage):
    name = "fit_polymer_coreflood"
    version = "3"  # 3: units in UDUNITS form (meq/ml written mmol/ml), issue 23
    description = "fit PERM, BRK, CRK to a single-phase polymer coreflood pressure history (Eqs. 2.6-2.8)"
    inputs = {"rheology": FIT}
    optional_inputs = frozenset({"rheology"})
    output = FIT
    params = {
        "path": Param(str, "", doc=_PATH_DOC),
        "fixed": Param(dict, {}, doc="forward-model parameters held fixed (UTCHEM names; default Table 2.4)"),
        "cells": Param(int, 30, bounds=(10, 2000), doc="grid cells of the simulator"),
    }

    def _path(self) -> Path:
        return _resolve(self.name, "path", self.params["path"], polymer_coreflood.KIND)

    def fingerprint(self) -> str:
        return _content_hash(self._path())

    def run(self, ctx: StageContext, rheology: xr.Dataset | None = None) -> xr.Dataset:
        fixed = {}
        if rheology is not None:  # the rheology fit's estimates replace the Table 2.4 polymer viscosity
            fixed.update({str(p): float(v) for p, v in zip(rheology["param"].values, rheology["estimate"].values)})
        fixed.update(self.params["fixed"])
        data = read_lab_table(self._path(), polymer_coreflood.KIND, polymer_coreflood.COLUMNS)
        return polymer_coreflood.fit_coreflood(data, fixed=fixed, cells=self.params["cells"])


class FitAdsorption(Stage):
    name = "fit_adsorption"
    version = "3"  # 3: units in UDUNITS form (meq/ml written mmol/ml), issue 23
    description = "fit Langmuir AD41/AD42/B4D or AD31/AD32/B3D to static retention data (Eqs. 2.15-2.16)"
    output = FIT
    params = {
        "component": Param(str, "polymer", choices=tuple(adsorption_fit.COMPONENTS), doc="adsorbing component"),
        "path": Param(str, "", doc=_PATH_DOC),
    }

    def _path(self) -> Path:
        kind = adsorption_fit.COMPONENTS[self.params["component"]][0]
        return _resolve(self.name, "path", self.params["path"], kind)

    def fingerprint(self) -> str:
        return _content_hash(self._path())

    def run(self, ctx: StageContext) -> xr.Dataset:
        component = self.params["component"]
        kind = adsorption_fit.COMPONENTS[component][0]
        data = read_lab_table(self._path(), kind, adsorption_fit.columns(component))
        return adsorption_fit.fit_adsorption(data, component)


class FitTracer(Stage):
    name = "fit_tracer"
    version = "3"  # 3: units in UDUNITS form (meq/ml written mmol/ml), issue 23
    description = "fit the dispersivity ALPHAL1 and the TDS-EC slope to an effluent conductivity curve (Fig. 2.9)"
    output = FIT
    params = {
        "path": Param(str, "", doc="effluent conductivity table; empty = bundled synthetic data"),
        "calibration_path": Param(str, "", doc="TDS-EC calibration table; empty = bundled synthetic data"),
    }

    def _paths(self) -> tuple[Path, Path]:
        return (_resolve(self.name, "path", self.params["path"], tracer_fit.KIND),
                _resolve(self.name, "calibration_path", self.params["calibration_path"], tracer_fit.CALIBRATION_KIND))

    def fingerprint(self) -> str:
        return _content_hash(*self._paths())

    def run(self, ctx: StageContext) -> xr.Dataset:
        effluent_path, calibration_path = self._paths()
        effluent = read_lab_table(effluent_path, tracer_fit.KIND, tracer_fit.COLUMNS)
        calibration = read_lab_table(calibration_path, tracer_fit.CALIBRATION_KIND, tracer_fit.CALIBRATION_COLUMNS)
        return tracer_fit.fit_tracer(effluent, calibration)
