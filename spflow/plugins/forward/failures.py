"""The ensemble failure policy, consumer side: samples whose forward runs failed (``forward`` stage: NaN rows and a
non-empty ``failure`` reason) are dropped with a warning saying how many, or rejected with an error where the method
needs every sample (e.g. a Sobol' design)."""

from __future__ import annotations

import warnings

import numpy as np
import xarray as xr

from spflow.core.errors import SpflowError

__all__ = ["failed_samples", "drop_failed", "reject_failed"]


def failed_samples(responses: xr.Dataset) -> np.ndarray:
    """Boolean mask over ``sample``: True where the forward run failed (no ``failure`` variable: none failed)."""
    if "failure" not in responses:
        return np.zeros(responses.sizes.get("sample", 0), dtype=bool)
    return np.array([str(r) != "" for r in responses["failure"].values], dtype=bool)


def _summary(responses: xr.Dataset, failed: np.ndarray) -> str:
    first = int(np.flatnonzero(failed)[0])
    return (f"{int(failed.sum())} of {failed.size} samples failed in the forward model (first: sample {first}: "
            f"{responses['failure'].values[first]})")


def drop_failed(responses: xr.Dataset, who: str) -> tuple[xr.Dataset, np.ndarray]:
    """``(responses without the failed samples, the kept positions)``; warns naming ``who`` and the count, and
    raises ``SpflowError`` if every sample failed."""
    failed = failed_samples(responses)
    keep = np.flatnonzero(~failed)
    if failed.any():
        if keep.size == 0:
            raise SpflowError(f"{who}: {_summary(responses, failed)}; no sample left to use")
        warnings.warn(f"{who}: dropped {_summary(responses, failed)}", stacklevel=2)
        responses = responses.isel(sample=keep)
    return responses, keep


def reject_failed(responses: xr.Dataset, who: str) -> None:
    """Raise ``SpflowError`` naming ``who`` and the count if any sample failed (for methods that need them all)."""
    failed = failed_samples(responses)
    if failed.any():
        raise SpflowError(f"{who}: {_summary(responses, failed)}; this method needs every sample of its design -- "
                          "narrow the parameter space or raise the forward budgets (max_steps, max_wall_s)")
