"""Quantities of interest of the screening (thesis §3.4): final oil recovery and maximum pressure drop per experiment,
and optionally every step of a response time series (per-time-step indices).

Input is a ``forward`` stage responses Dataset (dims ``sample``, ``experiment``, ``pv``), NaN-padded past each
experiment's end (``total_pv``). The QoI matrix is built by :func:`spflow.plugins.surrogates.outputs.stack_outputs`,
so screening QoIs carry the same (variable, experiment, pv) labels as surrogate outputs.
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from spflow.core.cf_metadata import squared_unit
from spflow.core.errors import SchemaError
from spflow.plugins.forward.stage import RESPONSE_UNITS
from spflow.plugins.surrogates.outputs import OutputIndex, stack_outputs

__all__ = ["SCALAR_QOIS", "QOI_CHOICES", "scalar_qois", "qoi_matrix", "qoi_coords"]

#: Scalar QoIs per experiment: name -> (response variable, unit).
SCALAR_QOIS = {"recovery_final": ("recovery", "1"), "dp_max": ("dp", "Pa")}
#: Allowed QoI names: the scalars, or a response variable for its per-time-step indices.
QOI_CHOICES = sorted(SCALAR_QOIS) + sorted(RESPONSE_UNITS)

_PV_TOL = 1e-9


def _inside(responses: xr.Dataset) -> xr.DataArray:
    """(experiment, pv) mask of the grid points up to each experiment's end."""
    return responses["pv"] <= responses["total_pv"] * (1 + _PV_TOL)


def scalar_qois(responses: xr.Dataset) -> xr.Dataset:
    """``recovery_final`` (recovery at each experiment's ``total_pv``, fraction OOIP) and ``dp_max`` (the largest
    pressure drop up to ``total_pv``, Pa), dims (``sample``, ``experiment``).

    The forward stage's common grid leaves an experiment NaN at the other experiments' off-step end points (for every
    sample); a NaN for some samples only (a broken run) raises :class:`SchemaError` instead of being skipped.
    """
    inside = _inside(responses)
    for name in ("recovery", "dp"):
        missing = responses[name].isnull()
        broken = (missing & ~missing.all("sample") & inside).transpose("sample", "experiment", "pv").values
        if broken.any():
            i, j, _ = np.argwhere(broken)[0]
            raise SchemaError(f"screening QoIs: response {name!r} is NaN for some samples only before the "
                              f"experiment's end (first at sample {i}, experiment "
                              f"{str(responses['experiment'].values[j])!r})")
    final = responses["recovery"].sel(pv=responses["total_pv"], method="nearest")
    off = np.abs(final["pv"].values - responses["total_pv"].values)
    if (off > _PV_TOL * np.maximum(1.0, responses["total_pv"].values)).any():
        raise SchemaError("screening QoIs: the responses' pv grid has no point at some experiment's total_pv")
    out = xr.Dataset({
        "recovery_final": final.drop_vars("pv").assign_attrs(units=SCALAR_QOIS["recovery_final"][1]),
        "dp_max": responses["dp"].where(inside).max("pv").assign_attrs(units=SCALAR_QOIS["dp_max"][1]),
    })
    return out.transpose("sample", "experiment")


def qoi_matrix(responses: xr.Dataset, qois: list[str]) -> tuple[np.ndarray, OutputIndex]:
    """``Y`` (n_sample, n_qoi) and its labels for the requested QoI names (``QOI_CHOICES``), per experiment.

    A scalar name gives one column per experiment; a response variable gives one column per output time of each
    experiment (up to its ``total_pv``).
    """
    scalars = scalar_qois(responses)
    inside = _inside(responses)
    parts = {name: scalars[name] if name in SCALAR_QOIS else responses[name].where(inside) for name in qois}
    return stack_outputs(xr.Dataset(parts), list(qois))


def qoi_coords(index: OutputIndex) -> dict[str, tuple]:
    """Coordinates of a ``qoi`` dim: a readable label (``dp_max:BCF1``, ``dp:BCF1@1.5``) and the variable,
    experiment, pv and unit of every column, and the square of the unit (of a variance)."""
    labels = [f"{v}:{e}" if np.isnan(p) else f"{v}:{e}@{p:.6g}"
              for v, e, p in zip(index.variable, index.experiment, index.pv)]
    units = [index.units[str(v)] for v in index.variable]
    return {
        "qoi": ("qoi", np.array(labels)),
        "qoi_variable": ("qoi", index.variable.astype(str)),
        "qoi_experiment": ("qoi", index.experiment.astype(str)),
        "qoi_pv": ("qoi", index.pv.astype(float), {"units": "1", "long_name": "injected pore volumes of the QoI"}),
        "qoi_units": ("qoi", np.array(units), {"long_name": "UDUNITS unit of the QoI"}),
        "qoi_units_squared": ("qoi", np.array([squared_unit(u) for u in units]),
                              {"long_name": "UDUNITS unit of the QoI squared"}),
    }
