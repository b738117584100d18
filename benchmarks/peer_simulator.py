"""spflow's own forward model as a test problem of ``bench_surrogates_peers.py`` (issue #24), with its runs cached.

The problem: BCF1 (thesis Table 2.5) on a coarse grid of ``CELLS`` cells, the 9 parameters of thesis Table 3.2
(``TABLE_3_2``, the screened space of the chapter-3 pipeline, docs/screening.md) uniform on their ranges, every other
parameter at its default. Outputs: Δp (Pa) and oil cut at the ``OUTPUT_PV`` injected pore volumes -- 2 x 10 columns
spanning the waterflood after breakthrough, the SP and polymer slugs and the start of the chase water (the 0.1 PV
output grid of the simulator, ``pv_step = 0.1``, sampled there).

One run costs ~7 ms of CPU at 30 cells, so runs are cheap next to the peers' fits; they are still cached, one
``.npz`` per design (keyed by a hash of the design and of this module's settings) under ``--cache``, so a repeated
or interrupted benchmark does not re-run them.
"""

from __future__ import annotations

import hashlib
from pathlib import Path

import numpy as np

from spflow.plugins.design.thesis_tables import TABLE_3_2

CELLS = 30
PV_STEP = 0.1
OUTPUT_PV = np.round(np.arange(0.5, 3.25, 0.3), 1)  # 0.5, 0.8, ..., 3.2
VARIABLES = ("dp", "oil_cut")
NAMES = list(TABLE_3_2)
LOWER, UPPER = (np.array(bound, dtype=float) for bound in zip(*TABLE_3_2.values()))
LABELS = [f"{variable}@{pv:g}" for variable in VARIABLES for pv in OUTPUT_PV]


def _settings() -> bytes:
    return repr((CELLS, PV_STEP, tuple(OUTPUT_PV), VARIABLES, NAMES)).encode()


def simulator_outputs(x: np.ndarray, cache: Path) -> np.ndarray:
    """Outputs (n, 20) of the forward model at the design ``x`` (n, 9), physical units; read from / written to the
    cache."""
    from spflow.plugins.forward.simulate import simulate

    key = hashlib.sha1(_settings() + np.ascontiguousarray(x, dtype=float).tobytes()).hexdigest()[:16]
    path = cache / f"bcf1_{x.shape[0]}_{key}.npz"
    if path.exists():
        return np.load(path)["y"]
    rows = []
    for point in x:
        ds = simulate("BCF1", dict(zip(NAMES, map(float, point))), cells=CELLS, pv_step=PV_STEP)
        at = [int(np.argmin(np.abs(ds["pv"].values - pv))) for pv in OUTPUT_PV]
        rows.append(np.concatenate([ds[variable].values[at] for variable in VARIABLES]))
    y = np.array(rows)
    cache.mkdir(parents=True, exist_ok=True)
    np.savez(path, x=x, y=y)
    return y
