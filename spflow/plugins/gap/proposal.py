"""Write the proposed next experiment: its schedule file and the rationale a lab reads.

From the ranked table of :func:`~spflow.plugins.gap.next_experiment.rank_designs`, :func:`write_proposal` writes

* ``next_experiment.toml`` — the chosen design's schedule in the schedule-file format of
  :mod:`spflow.io.schedule_file` (per-slug ``rate_ml_min`` where the design sets a rate);
* ``next_experiment.json`` — why: the hypotheses, the design's label and kind, its decision accuracy per hypothesis
  and the truth's over-dispersion on it (``truth_dispersion``), its predicted power and expected log predictive ratio
  per (truth, alternative) pair, its injected PV and duration, the runner-up designs, and the assumptions the ranking
  made (base rate and its source, noise model source, how the lab data were simulated, decision margins, criterion).

The same design as an experiment of a study file: :func:`spflow.study.proposed_experiment.study_experiment_toml`
(the study package depends on this one, not the reverse).
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import xarray as xr

from spflow.core.errors import ParameterError
from spflow.io.schedule_file import write_schedule_file
from spflow.plugins.forward.schedule import as_schedule

__all__ = ["write_proposal", "proposal_summary"]


def _number(x) -> float | None:
    x = float(x)
    return x if np.isfinite(x) else None


def proposal_summary(table: xr.Dataset, rank: int = 1, runners_up: int = 4) -> dict:
    """The rationale of the design ranked ``rank`` (1 = best) as a JSON-ready dict (module docstring)."""
    n = table.sizes["design"]
    if not isinstance(rank, int) or isinstance(rank, bool) or not 1 <= rank <= n:
        raise ParameterError(f"rank must be an integer in [1, {n}] (the ranked designs), got {rank!r}")
    row = table.isel(design=int(np.flatnonzero(table["rank"].values == rank)[0]))
    names = json.loads(table.attrs["hypotheses"])
    pairs = [{"truth": a, "alternative": b,
              "expected_log_ratio_nat": _number(row["expected_log_ratio"].sel(truth=a, alternative=b)),
              "log_ratio_sd_nat": _number(row["log_ratio_sd"].sel(truth=a, alternative=b)),
              "decision_margin_nat": _number(row["decision_margin"].sel(truth=a, alternative=b)),
              "power": _number(row["power"].sel(truth=a, alternative=b))}
             for a in names for b in names if a != b]
    ranks = table["rank"].values
    others = [table.isel(design=int(i)) for i in np.argsort(ranks) if ranks[i] != rank][:runners_up]
    return {
        "label": str(row["label"].values),
        "kind": str(row["kind"].values),
        "rank": rank,
        "schedule": json.loads(str(row["schedule"].values)),
        "total_pv": float(row["total_pv"]),
        "duration_h": _number(row["duration"]),
        "worst_accuracy": _number(row["worst_accuracy"]),
        "mean_accuracy": _number(row["mean_accuracy"]),
        "accuracy": {a: _number(row["accuracy"].sel(truth=a)) for a in names},
        "truth_dispersion": {a: _number(row["truth_dispersion"].sel(truth=a)) for a in names},
        "worst_expected_log_ratio_nat": _number(row["worst_expected_log_ratio"]),
        "separation_by_slug": json.loads(str(row["separation_by_slug"].values)),
        "pairs": pairs,
        "hypotheses": names,
        "runners_up": [{"label": str(o["label"].values), "worst_accuracy": _number(o["worst_accuracy"]),
                        "worst_expected_log_ratio_nat": _number(o["worst_expected_log_ratio"])}
                       for o in others],
        "assumptions": {key: table.attrs[key] for key in (
            "reference_experiment", "variables", "criterion", "min_delta", "se_factor", "draws", "seed",
            "base_rate_ml_min",
            "base_rate_source", "noise_model_source", "parameter_uncertainty", "truth_data", "dispersion_correction",
            "method", "hypotheses_source", "accuracy_caveat") if key in table.attrs},
    }


def write_proposal(table: xr.Dataset, directory, rank: int = 1) -> dict[str, Path]:
    """Write ``next_experiment.toml`` and ``next_experiment.json`` for the design ranked ``rank`` into
    ``directory`` (created if needed); returns ``{"schedule": path, "rationale": path}``."""
    summary = proposal_summary(table, rank)
    out = Path(directory)
    out.mkdir(parents=True, exist_ok=True)
    schedule = write_schedule_file(as_schedule(summary["schedule"]), out / "next_experiment.toml")
    rationale = out / "next_experiment.json"
    rationale.write_text(json.dumps(summary, indent=2))
    return {"schedule": schedule, "rationale": rationale}
