"""Stage ``breakthrough``: polymer breakthrough and peak pressure drop of every simulated coreflood.

Input: the ``forward`` stage's responses (dims ``sample``, ``experiment``, ``pv``) with ``c_polymer_out`` [ppm]
and ``dp`` [Pa]. Output per (sample, experiment): ``polymer_breakthrough_pv`` -- the injected PV at which the
effluent polymer concentration first reaches ``fraction`` of its maximum, linearly interpolated between output
points (NaN when no polymer leaves the core) -- and ``dp_peak`` [Pa] with its PV ``dp_peak_pv``.
"""

import numpy as np
import xarray as xr

import spflow

RESPONSES = spflow.DatasetSchema(
    dims=("sample", "experiment", "pv"),
    variables={"dp": spflow.Variable(("sample", "experiment", "pv"), units="Pa"),
               "c_polymer_out": spflow.Variable(("sample", "experiment", "pv"), units="ppm")},
)


def first_crossing(pv: np.ndarray, values: np.ndarray, level: float) -> float:
    """The first ``pv`` where ``values`` reaches ``level``, interpolated linearly; NaN if it never does."""
    above = np.flatnonzero(values >= level)
    if above.size == 0:
        return float("nan")
    k = int(above[0])
    if k == 0:
        return float(pv[0])
    return float(np.interp(level, values[k - 1:k + 1], pv[k - 1:k + 1]))


class Breakthrough(spflow.Stage):
    name = "breakthrough"
    version = "1"
    description = "polymer breakthrough PV and peak pressure drop per simulated coreflood"
    inputs = {"responses": RESPONSES}
    output = spflow.DatasetSchema(
        dims=("sample", "experiment"),
        variables={"polymer_breakthrough_pv": spflow.Variable(("sample", "experiment"), units="PV",
                                                              allow_nan=True),
                   "dp_peak": spflow.Variable(("sample", "experiment"), units="Pa"),
                   "dp_peak_pv": spflow.Variable(("sample", "experiment"), units="PV")},
    )
    params = {"fraction": spflow.Param(float, 0.5, bounds=(0.01, 0.99),
                                       doc="breakthrough level as a fraction of the maximum effluent polymer")}

    def run(self, ctx, responses):
        pv = responses["pv"].values
        cp = responses["c_polymer_out"].values
        dp = responses["dp"].values
        shape = cp.shape[:2]
        breakthrough = np.full(shape, np.nan)
        for s, e in np.ndindex(shape):
            peak = np.nanmax(cp[s, e])
            if peak > 0:
                breakthrough[s, e] = first_crossing(pv, np.nan_to_num(cp[s, e]), self.params["fraction"] * peak)
        k = np.nanargmax(dp, axis=2)
        dims = ("sample", "experiment")
        return xr.Dataset(
            {"polymer_breakthrough_pv": (dims, breakthrough, {"units": "PV"}),
             "dp_peak": (dims, np.take_along_axis(dp, k[..., None], axis=2)[..., 0], {"units": "Pa"}),
             "dp_peak_pv": (dims, pv[k], {"units": "PV"})},
            coords={"sample": responses["sample"].values, "experiment": responses["experiment"].values},
            attrs={"fraction": self.params["fraction"]},
        )
