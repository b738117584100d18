"""The ``quantiles`` stage: ensemble quantiles and mean over the ``sample`` dimension (prior/posterior spread)."""

from __future__ import annotations

import warnings

import numpy as np
import xarray as xr

from spflow.core.params import Param
from spflow.core.schema import DatasetSchema
from spflow.core.stage import Stage, StageContext


class Quantiles(Stage):
    name = "quantiles"
    description = "quantiles and mean of every variable over the sample dimension"
    inputs = {"ensemble": DatasetSchema(dims=("sample",))}
    output = DatasetSchema(dims=("quantile",))
    params = {"levels": Param(list, [0.1, 0.5, 0.9], bounds=(0.0, 1.0), doc="quantile levels in [0, 1]")}

    def run(self, ctx: StageContext, ensemble: xr.Dataset) -> xr.Dataset:
        per_sample = [v for v in ensemble.data_vars if "sample" in ensemble[v].dims]
        # numbers only: a per-sample text variable (the forward stage's ``failure`` reasons) has no quantiles; failed
        # samples are NaN rows, which the quantiles skip, and their count is recorded
        varying = [v for v in per_sample if ensemble[v].dtype.kind in "fiu"]
        sub = ensemble[varying]
        with warnings.catch_warnings():  # NaN padding past an experiment's end is all-NaN across samples
            warnings.simplefilter("ignore", RuntimeWarning)
            out = sub.quantile(np.asarray(self.params["levels"], dtype=float), dim="sample")
        mean = sub.mean("sample")
        for v in varying:
            out[f"{v}_mean"] = mean[v]
            out[v].attrs = dict(ensemble[v].attrs)
            out[f"{v}_mean"].attrs = dict(ensemble[v].attrs)
            if "long_name" in ensemble[v].attrs:
                out[f"{v}_mean"].attrs["long_name"] = f"ensemble mean of {ensemble[v].attrs['long_name']}"
        out["quantile"].attrs.update(units="1", long_name="quantile level")
        for v in ensemble.data_vars:
            if v not in per_sample:
                out[v] = ensemble[v]
        out.attrs = dict(ensemble.attrs, ensemble_size=ensemble.sizes["sample"])
        if "failure" in ensemble:
            out.attrs["failed_samples"] = int(sum(bool(str(r)) for r in ensemble["failure"].values))
        return out
