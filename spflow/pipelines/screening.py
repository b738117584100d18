"""Thesis §3.3-3.4: Sobol' screening of the 19 Table 3.1 parameters per sub-model on a study's first training
coreflood (Fig. 3.2; bundled study: BCF1, as in the thesis), simulated with its own core, rate and schedule.

Each sub-model is varied alone over its Table 3.1 range with the others at the Table 2.4 defaults (the thesis's
Algorithm 1); total indices of final recovery and maximum pressure drop decide which parameters the proxy keeps.
The report compares the selection with the thesis's Table 3.2.

    spflow run screening --jobs 2
"""

from __future__ import annotations

from pathlib import Path

import spflow
from spflow.plugins.design.thesis_tables import TABLE_3_2
from spflow.plugins.screening.table_3_1 import TABLE_3_1, TABLE_3_1_RANGES, table_3_1_names
from spflow.study.pipeline_inputs import StudyInputs

#: the scalar QoIs of Fig. 3.2 (per screened experiment)
QOIS = ["recovery_final", "dp_max"]


def pipeline(samples: int = 64, cells: int = 100, threshold: float = 0.1, seed: int = 2024, study=None,
             quick: bool = False) -> spflow.Pipeline:
    """``samples``: Sobol' base size N (power of two; N (d + 2) runs per sub-model of d parameters); ``study``: a
    study file, a Study or ``None`` (the bundled study): its first ``calibration`` experiment is screened."""
    if quick:
        samples, cells = 8, 40
    inputs = StudyInputs.of(study)
    p = spflow.Pipeline("screening_quick" if quick else "screening")
    p.add("space", "parameter_space", params={"names": table_3_1_names(), "ranges": TABLE_3_1_RANGES})
    p.add("screening", "sobol_screening", inputs={"space": "space"},
          params={"experiments": inputs.forward(inputs.training[:1]), **inputs.model(), "samples": samples,
                  "cells": cells, "groups": TABLE_3_1,
                  "mode": "per_group", "threshold": threshold, "seed": seed})
    return p


def report(result: spflow.RunResult, outdir: Path) -> list[str]:
    """Fig. 3.2 and the per-parameter total indices against the thesis's choice (Table 3.2)."""
    from spflow.plugins.screening.figure import plot_total_indices

    screening = result["screening"]
    experiment = screening.attrs["experiments"]
    qois = [f"{q}:{experiment}" for q in QOIS]
    fig = plot_total_indices(screening, qois, title=f"Fig. 3.2: Sobol' screening on {experiment} "
                                                    f"({screening.attrs['runs']} runs)")
    fig.savefig(outdir / "fig_3_2_sobol_screening.png", dpi=110)
    lines = [f"{screening.attrs['runs']} simulations; selection: {screening.attrs['selection_rule']}",
             f"{'sub-model':28s} {'param':8s} {'ST recovery':>12s} {'ST max dp':>12s}  selected  thesis"]
    for name in screening["param"].values:
        row = screening.sel(param=name)
        st = [f"{float(row['ST'].sel(qoi=q)):6.3f}±{float(row['ST_conf'].sel(qoi=q)):.3f}" for q in qois]
        lines.append(f"{str(row['group'].values):28s} {name:8s} {st[0]:>12s} {st[1]:>12s}  "
                     f"{'yes' if bool(row['selected']) else '-':8s}  {'yes' if name in TABLE_3_2 else '-'}")
    ours = {str(n) for n in screening["param"].values[screening["selected"].values.astype(bool)]}
    lines.append(f"selected {len(ours)}, thesis {len(TABLE_3_2)}: both {sorted(ours & set(TABLE_3_2))}; only ours "
                 f"{sorted(ours - set(TABLE_3_2))}; only thesis {sorted(set(TABLE_3_2) - ours)}")
    return lines
