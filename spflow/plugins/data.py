"""Source stages that bring external data into a pipeline, keyed by content (never by path or object identity)."""

from __future__ import annotations

from pathlib import Path

import xarray as xr

from spflow.core.errors import ParameterError
from spflow.core.hashing import canonical_hash
from spflow.core.params import Param
from spflow.core.stage import Stage, StageContext

__all__ = ["DataStage", "LoadNetCDF"]


class DataStage(Stage):
    """An in-memory Dataset added with ``Pipeline.add_data``; its provenance is its canonical content hash."""

    name = "data"
    description = "in-memory Dataset (content-hashed)"

    @classmethod
    def holding(cls, dataset: xr.Dataset) -> "DataStage":
        stage = cls()
        stage._dataset = dataset
        stage._hash = canonical_hash(dataset)
        return stage

    def fingerprint(self) -> str:
        return self._hash

    def run(self, ctx: StageContext) -> xr.Dataset:
        return self._dataset.copy()


class LoadNetCDF(Stage):
    """Load a netCDF file (e.g. observations); the key follows the file's content, not its path or mtime."""

    name = "load_netcdf"
    description = "load a netCDF file (content-hashed)"
    params = {"path": Param(str, doc="path of the netCDF file")}

    def _load(self) -> xr.Dataset:
        """The file's content, read once per stage instance (the fingerprint and ``run`` share it)."""
        if getattr(self, "_dataset", None) is None:
            path = Path(self.params["path"])
            if not path.is_file():
                raise ParameterError(f"stage 'load_netcdf' parameter 'path': no such file {str(path)!r}")
            with xr.open_dataset(path) as ds:
                self._dataset = ds.load().drop_encoding()
        return self._dataset

    def fingerprint(self) -> str:
        return canonical_hash(self._load())

    def run(self, ctx: StageContext) -> xr.Dataset:
        return self._load().copy()
