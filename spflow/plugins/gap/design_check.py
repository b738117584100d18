"""Check a design's predicted decision accuracy by running the lab: simulated corefloods scored like held-out data.

:func:`realised_accuracy` is the end-to-end counterpart of :func:`~spflow.plugins.gap.next_experiment.
rank_designs`' simulated accuracy. For each hypothesis taken as the truth it draws ``seeds`` parameter sets from
the hypothesis's calibration covariance (clipped to the unit box), makes a lab-like coreflood of the design with
each (:func:`spflow.synthetic.make_coreflood`: the reference's core and measurement chain, its random errors
included -- the transducer's AR(1) noise at its own sampling, uniform tube-reading errors, offset, drift and dead
volume), reads it back as the diagnosis does (:func:`~spflow.plugins.gap.observed.load_experiments`), scores every
hypothesis on it as held-out data (:func:`~spflow.plugins.gap.predictive_scores.predictive`) and applies the
decision rule to the truth against each alternative (``dELPD > min_delta`` and ``> se_factor`` measurement SE, the SE
times ``sqrt(max(1, phi_truth, phi_alternative))`` with the diagnosis's over-dispersion correction, ``phi`` a model's
mean square whitened residual on the flood; :mod:`~spflow.plugins.gap.verdict`).
The fraction of seeds where the truth passes against every alternative is its realised accuracy. Nothing here is
Gaussian or linearised except the predictive densities the diagnosis itself uses, so a design whose predicted and
realised accuracies disagree shows where the designer's approximations fail.
"""

from __future__ import annotations

import json
from collections.abc import Sequence

import numpy as np
import xarray as xr

from spflow.core.errors import ParameterError
from spflow.plugins.forward.schedule import as_schedule
from spflow.synthetic import make_coreflood

from .base_model import BaseModel
from .layout import make_layout
from .least_squares import model_point
from .next_experiment import Hypothesis
from .observed import Experiment, load_experiments
from .prediction import Predictor
from .predictive_scores import compare, predictive
from .verdict import Rule, significant

__all__ = ["realised_accuracy"]


def realised_accuracy(table: xr.Dataset, hypotheses: Sequence[Hypothesis], base: BaseModel, reference: Experiment,
                      rank: int = 1, *, seeds: int = 20, tau: float = 0.5, first_seed: int = 0,
                      diff_step: float = 0.01, dispersion: bool = True) -> xr.DataArray:
    """Realised decision accuracy (dims ``truth``, units 1) of the design ranked ``rank`` in ``table`` (from
    :func:`~spflow.plugins.gap.next_experiment.rank_designs` with the same ``hypotheses``, ``base`` and
    ``reference``) over ``seeds`` simulated corefloods per true hypothesis (module docstring). ``tau`` must be the
    prior scale of the hypotheses' covariances (:func:`~spflow.plugins.gap.next_experiment.hypotheses_from_fits`);
    ``dispersion`` applies the over-dispersion correction of the SE (module docstring)."""
    names = [h.name for h in hypotheses]
    if names != [str(x) for x in table["truth"].values]:
        raise ParameterError(f"hypotheses {names} are not those of the table {list(table['truth'].values)}")
    if isinstance(seeds, bool) or not isinstance(seeds, int) or seeds < 1:
        raise ParameterError(f"seeds must be an integer >= 1, got {seeds!r}")
    ranks = table["rank"].values
    if rank not in ranks:
        raise ParameterError(f"rank must be one of 1..{ranks.size}, got {rank!r}")
    row = table.isel(design=int(np.flatnonzero(ranks == rank)[0]))
    schedule = as_schedule(json.loads(str(row["schedule"].values)))
    variables = json.loads(table.attrs["variables"])
    rule = Rule(min_delta=float(table.attrs["min_delta"]), se_factor=float(table.attrs["se_factor"]))
    passes = np.zeros(len(hypotheses), int)
    for a, truth in enumerate(hypotheses):
        own = truth.base or base
        rng = np.random.default_rng(first_seed + a)
        for k in range(seeds):
            z = truth.fit.z if truth.covariance is None else np.clip(
                rng.multivariate_normal(truth.fit.z, truth.covariance, method="eigh"), 0.0, 1.0)
            params, effects = Predictor(own, []).model(*model_point(z, truth.fit.n_params, truth.fit.candidates))
            lab = make_coreflood(schedule, {**reference.core, **params}, effects=effects, noise=reference.measurement,
                                 seed=first_seed + k, cells=own.cells, pv_step=own.pv_step, experiment="design")
            [exp] = load_experiments([lab], reference.pv_step)
            layout = make_layout([exp], variables)
            scores = [predictive(Predictor(h.base or base, [exp]), layout, h.fit, tau, diff_step) for h in hypotheses]
            phi = [float(np.nanmean(x.whitened**2)) if dispersion else 1.0 for x in scores]
            passed = True
            for b in range(len(hypotheses)):
                if b != a:
                    delta, se, _ = compare(scores[a], scores[b])
                    passed &= significant(delta, se, max(phi[a], phi[b]), rule)
            passes[a] += passed
    return xr.DataArray(passes / seeds, dims=("truth",), coords={"truth": names},
                        attrs={"units": "1", "long_name": f"realised decision accuracy over {seeds} simulated "
                               f"corefloods of design {rank} ({row['label'].values})"})
