"""Observed values aligned with a surrogate's (or the simulator's) output columns.

Both calibrations compare a prediction vector (columns labelled variable / experiment / PV, see
:class:`~spflow.plugins.surrogates.outputs.OutputIndex`) with measurements put on the simulator grid by the
``observations`` stage. This module pairs them by label, so the misfits of Eqs. 3.16-3.17 and the likelihood of
§4.5 are plain differences of equal-length vectors.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import xarray as xr

from spflow.core.errors import ParameterError
from spflow.plugins.surrogates.outputs import OutputIndex

__all__ = ["AlignedData", "align"]


@dataclass(frozen=True)
class AlignedData:
    """Observed values for the usable output columns of one (variable, experiment) pair each.

    ``blocks`` maps (variable, experiment) -> (column numbers in the prediction, observed values, PV); only columns
    with a finite observation are kept.
    """

    blocks: dict[tuple[str, str], tuple[np.ndarray, np.ndarray, np.ndarray]]

    def observed(self, variable: str, experiment: str) -> np.ndarray:
        return self.blocks[(variable, experiment)][1]

    def predicted(self, prediction: np.ndarray, variable: str, experiment: str) -> np.ndarray:
        """The columns of ``prediction`` (..., n_output) that pair with ``observed(variable, experiment)``."""
        return prediction[..., self.blocks[(variable, experiment)][0]]


def align(index: OutputIndex, observations: xr.Dataset, pairs: list[tuple[str, str]]) -> AlignedData:
    """Pair each (variable, experiment) of ``pairs`` between prediction columns ``index`` and ``observations``
    (dims experiment, pv). An unknown pair or one with no overlapping finite observation raises before any work."""
    blocks = {}
    for variable, experiment in pairs:
        if variable not in observations or experiment not in observations["experiment"].values:
            raise ParameterError(f"no observation of {variable!r} for experiment {experiment!r}; observations have "
                                 f"variables {sorted(map(str, observations.data_vars))} and experiments "
                                 f"{[str(e) for e in observations['experiment'].values]}")
        cols = index.columns(variable, experiment)
        pv = index.pv[cols]
        series = observations[variable].sel(experiment=experiment)
        lookup = dict(zip(np.round(series["pv"].values, 9), series.values))
        obs = np.array([lookup.get(round(float(x), 9), np.nan) for x in pv])
        keep = np.isfinite(obs)
        if not keep.any():
            raise ParameterError(f"observations of {variable!r} for {experiment!r} share no PV with the predictions "
                                 f"(predicted PV {pv.min():g}..{pv.max():g})")
        blocks[(variable, experiment)] = (cols[keep], obs[keep], pv[keep])
    return AlignedData(blocks)
