"""The ``surrogate_validation`` stage: any surrogate against simulator runs on an independent design (§3.5.3-3.5.5).

Per output column: the coefficient of determination R² = 1 − Σ(y − ŷ)² / Σ(y − ȳ)² and the relative validation
error mean((y − ŷ)²) / Var̂(y). Per QoI (variable, experiment): R² of the final value (e.g. final recovery) and of the
maximum over PV (e.g. max Δp) — the scalar QoIs of Figs. 3.4-3.5 — and the relative L2 errors (Eq. 3.15) of the
proxy's mean and variance curves against the sample mean I_n (Eq. 3.13) and population variance V_n (Eq. 3.14) of the
simulator runs. The proxy's moments are the surrogate's own analytic ones when its kind provides ``moments()`` (the
PCE: Eqs. 3.11-3.12); otherwise the sample moments of its predicted mean at the validation points.

Works for every surrogate kind: the surrogate is rebuilt with :func:`~.contract.load_surrogate` and only its contract
(``predict``, ``outputs``) is used.
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from spflow.core.errors import ParameterError
from spflow.core.schema import DatasetSchema, Variable
from spflow.core.stage import Stage, StageContext
from spflow.plugins.design.schemas import DESIGN

from .contract import SURROGATE, load_surrogate
from .outputs import OutputIndex, stack_outputs
from .regression import is_constant
from .training_data import design_points

__all__ = ["SurrogateValidation", "VALIDATION", "matching_columns", "r_squared", "relative_l2"]

VALIDATION = DatasetSchema(
    dims=("output", "qoi"),
    variables={
        "r2": Variable(("output",), units="1", allow_nan=True, long_name="coefficient of determination per output"),
        "relative_error": Variable(("output",), units="1", allow_nan=True, long_name="relative L2 error per output"),
        "r2_final": Variable(("qoi",), units="1", allow_nan=True, long_name="R2 at the last output of the QoI"),
        "r2_max": Variable(("qoi",), units="1", allow_nan=True, long_name="largest R2 over the QoI's outputs"),
        "mean_l2_error": Variable(("qoi",), units="1", allow_nan=True, long_name="relative L2 error of the mean"),
        "variance_l2_error": Variable(("qoi",), units="1", allow_nan=True,
                                      long_name="relative L2 error of the variance"),
    },
    doc="surrogate accuracy on an independent design",
)


def r_squared(truth: np.ndarray, predicted: np.ndarray) -> np.ndarray:
    """R² per column (NaN for a constant column, :func:`.regression.is_constant`)."""
    ss_res = np.sum((truth - predicted) ** 2, axis=0)
    ss_tot = np.sum((truth - truth.mean(axis=0)) ** 2, axis=0)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(is_constant(truth.reshape(truth.shape[0], -1)).reshape(ss_tot.shape), np.nan,
                        1.0 - ss_res / ss_tot)


def relative_l2(truth: np.ndarray, estimate: np.ndarray) -> float:
    """Eq. 3.15: ||truth − estimate||₂ / ||truth||₂."""
    norm = np.linalg.norm(truth)
    return float(np.linalg.norm(truth - estimate) / norm) if norm > 0 else float("nan")


def matching_columns(responses: xr.Dataset, outputs: OutputIndex) -> np.ndarray:
    """The columns of ``responses`` (sample, output) that carry the surrogate's outputs, in the surrogate's order."""
    variables = list(dict.fromkeys(str(v) for v in outputs.variable))
    experiments = [e for e in dict.fromkeys(str(e) for e in outputs.experiment) if e]
    y, index = stack_outputs(responses, variables, experiments or None)
    columns = np.empty(len(outputs), dtype=np.int64)
    for k in range(len(outputs)):
        same = (index.variable == outputs.variable[k]) & (index.experiment == outputs.experiment[k])
        same &= np.isclose(index.pv, outputs.pv[k], rtol=0, atol=1e-9) | (np.isnan(index.pv) & np.isnan(outputs.pv[k]))
        if not same.any():
            raise ParameterError(f"surrogate_validation: the responses have no column for output {k} "
                                 f"({outputs.variable[k]}, {outputs.experiment[k] or '-'}, pv={outputs.pv[k]:g})")
        columns[k] = int(np.flatnonzero(same)[0])
    return y[:, columns]


class SurrogateValidation(Stage):
    name = "surrogate_validation"
    version = "1"
    description = "R², relative errors and moment errors (Eq. 3.15) of any surrogate on an independent design"
    inputs = {"surrogate": SURROGATE, "design": DESIGN, "responses": DatasetSchema(dims=("sample",))}
    output = VALIDATION
    params = {}

    def run(self, ctx: StageContext, surrogate: xr.Dataset, design: xr.Dataset, responses: xr.Dataset) -> xr.Dataset:
        model = load_surrogate(surrogate)
        x = design_points(design, model.names, model.lower, model.upper)
        if responses.sizes["sample"] != x.shape[0]:
            raise ParameterError(f"surrogate_validation: the responses have {responses.sizes['sample']} samples, the "
                                 f"design {x.shape[0]} points")
        truth = matching_columns(responses, model.outputs)
        predicted, _ = model.predict(x)
        analytic = getattr(model, "moments", None)
        proxy_mean, proxy_var = analytic() if analytic else (predicted.mean(axis=0), predicted.var(axis=0))
        groups = list(dict.fromkeys(zip(model.outputs.variable.astype(str), model.outputs.experiment.astype(str))))
        per_qoi = {name: np.empty(len(groups)) for name in VALIDATION.variables if name not in ("r2", "relative_error")}
        for g, (variable, experiment) in enumerate(groups):
            cols = model.outputs.columns(variable, experiment)
            per_qoi["r2_final"][g] = r_squared(truth[:, cols[-1]], predicted[:, cols[-1]])
            per_qoi["r2_max"][g] = r_squared(truth[:, cols].max(axis=1), predicted[:, cols].max(axis=1))
            per_qoi["mean_l2_error"][g] = relative_l2(truth[:, cols].mean(axis=0), proxy_mean[cols])
            per_qoi["variance_l2_error"][g] = relative_l2(truth[:, cols].var(axis=0), proxy_var[cols])
        with np.errstate(divide="ignore", invalid="ignore"):
            relative = np.where(is_constant(truth), np.nan, np.mean((truth - predicted) ** 2, axis=0)
                                / truth.var(axis=0))
        ds = xr.Dataset(
            {"r2": ("output", r_squared(truth, predicted), {"units": "1"}),
             "relative_error": ("output", relative, {"units": "1", "long_name": "mean squared error / Var(y)"}),
             **{name: ("qoi", values, {"units": "1"}) for name, values in per_qoi.items()}},
            coords={**model.outputs.coords(), "qoi_variable": ("qoi", [v for v, _ in groups]),
                    "qoi_experiment": ("qoi", [e for _, e in groups])},
        )
        ds.attrs = {"surrogate": surrogate.attrs["surrogate"], "n_validation": x.shape[0],
                    "moments": "analytic" if analytic else "sample moments of the predicted mean",
                    **model.outputs.unit_attrs()}
        return ds
