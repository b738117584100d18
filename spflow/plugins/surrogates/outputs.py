"""Flatten simulator responses into a (sample, output) matrix and back.

A surrogate learns a vector of outputs per parameter vector: the thesis's time series of each QoI on the 0.1 PV
grid (the ε^mean of Eqs. 3.9-3.10 averages over them) or scalar QoIs such as final recovery. Every output column is
labelled by the variable it comes from and by its coordinates along the remaining dims (``experiment``, ``pv``);
columns that are NaN for every sample (an experiment's padding past its end) are dropped.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import xarray as xr

from spflow.core.cf_metadata import squared_unit, udunits
from spflow.core.errors import ParameterError

__all__ = ["OutputIndex", "stack_outputs"]

#: Dims an output column may be labelled by (missing ones are stored as "" / NaN).
LABEL_DIMS = ("experiment", "pv")


@dataclass(frozen=True)
class OutputIndex:
    """Labels of output columns: ``variable[k]``, ``experiment[k]`` ("" if none), ``pv[k]`` (NaN if none), ``units``."""

    variable: np.ndarray
    experiment: np.ndarray
    pv: np.ndarray
    units: dict[str, str]

    def __len__(self) -> int:
        return int(self.variable.size)

    @classmethod
    def of_array(cls, m: int, variable: str = "y", unit: str = "1") -> OutputIndex:
        """The index of ``m`` plain array columns: all labelled ``variable`` (so ``share="variable"`` makes them share
        length scales), no experiment, no PV, one ``unit`` (``"1"`` when the caller does not know y's unit)."""
        return cls(np.full(m, variable), np.full(m, ""), np.full(m, np.nan), {variable: unit})

    def columns(self, variable: str, experiment: str | None = None) -> np.ndarray:
        """Column numbers of one variable (and experiment), in increasing ``pv``."""
        mask = self.variable == variable
        if experiment is not None:
            mask &= self.experiment == experiment
        if not mask.any():
            have = sorted({(str(v), str(e)) for v, e in zip(self.variable, self.experiment)})
            raise ParameterError(f"no surrogate output for variable {variable!r}, experiment {experiment!r}; "
                                 f"outputs cover {have}")
        cols = np.flatnonzero(mask)
        return cols[np.argsort(self.pv[cols], kind="stable")]

    def coords(self) -> dict[str, tuple]:
        """Coordinates on an ``output`` dim, for storing the index in a Dataset; ``output_unit`` and
        ``output_unit_squared`` (UDUNITS) are what values and variances per output column are in (units per element,
        :mod:`spflow.core.cf_metadata`)."""
        unit = [udunits(self.units.get(str(v), "1")) for v in self.variable]
        return {"output_variable": ("output", self.variable.astype(str), {"long_name": "variable of the output"}),
                "output_experiment": ("output", self.experiment.astype(str),
                                      {"long_name": "coreflood of the output (empty: none)"}),
                "output_pv": ("output", self.pv.astype(float), {"units": "1", "long_name": "injected pore volumes "
                                                                                          "of the output (NaN: none)"}),
                "output_unit": ("output", np.array(unit, dtype=str), {"long_name": "UDUNITS unit of the output"}),
                "output_unit_squared": ("output", np.array([squared_unit(u) for u in unit], dtype=str),
                                        {"long_name": "UDUNITS unit of the output's square"})}

    @classmethod
    def from_dataset(cls, ds: xr.Dataset) -> OutputIndex:
        units = {str(k[len("units_"):]): str(v) for k, v in ds.attrs.items() if k.startswith("units_")}
        return cls(ds["output_variable"].values.astype(str), ds["output_experiment"].values.astype(str),
                   ds["output_pv"].values.astype(float), units)

    def unit_attrs(self) -> dict[str, str]:
        """Dataset attrs recording each variable's unit (``units_<variable>``)."""
        return {f"units_{k}": v for k, v in self.units.items()}


def stack_outputs(responses: xr.Dataset, variables: list[str],
                  experiments: list[str] | None = None) -> tuple[np.ndarray, OutputIndex]:
    """Return ``Y`` (n_sample, n_output) and its :class:`OutputIndex` for ``variables`` of ``responses``.

    ``responses`` has dim ``sample`` and, per variable, any of ``experiment``/``pv``. ``experiments`` restricts the
    ``experiment`` dim. Columns that are NaN for every sample are dropped; a NaN anywhere else is an error.
    """
    missing = [v for v in variables if v not in responses.data_vars]
    if missing:
        raise ParameterError(f"surrogate outputs: unknown variable {missing[0]!r}; "
                             f"available: {sorted(map(str, responses.data_vars))}")
    if experiments is not None and "experiment" in responses.dims:
        unknown = [e for e in experiments if e not in responses["experiment"].values]
        if unknown:
            raise ParameterError(f"surrogate outputs: unknown experiment {unknown[0]!r}; available: "
                                 f"{[str(e) for e in responses['experiment'].values]}")
        responses = responses.sel(experiment=list(experiments))
    blocks, var_l, exp_l, pv_l, units = [], [], [], [], {}
    for name in variables:
        da = responses[name]
        extra = [d for d in da.dims if d != "sample"]
        if any(d not in LABEL_DIMS for d in extra):
            raise ParameterError(f"surrogate outputs: variable {name!r} has dims {da.dims}; allowed besides "
                                 f"'sample': {LABEL_DIMS}")
        da = da.transpose("sample", *[d for d in LABEL_DIMS if d in extra])
        flat = da.values.reshape(da.sizes["sample"], -1)
        grids = np.meshgrid(*[da[d].values for d in da.dims[1:]], indexing="ij") if extra else []
        labels = {d: g.ravel() for d, g in zip(da.dims[1:], grids)}
        keep = ~np.isnan(flat).all(axis=0)
        if np.isnan(flat[:, keep]).any():
            raise ParameterError(f"surrogate outputs: variable {name!r} has NaN for some samples only")
        blocks.append(flat[:, keep])
        var_l.append(np.full(keep.sum(), name))
        exp_l.append(labels["experiment"][keep].astype(str) if "experiment" in labels else np.full(keep.sum(), ""))
        pv_l.append(labels["pv"][keep].astype(float) if "pv" in labels else np.full(keep.sum(), np.nan))
        units[name] = str(da.attrs.get("units", "1"))
    index = OutputIndex(np.concatenate(var_l), np.concatenate(exp_l), np.concatenate(pv_l), units)
    return np.concatenate(blocks, axis=1), index
