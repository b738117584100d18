"""Polymer breakthrough of BCF2 across a small design of polymer adsorption and permeability reduction.

The example plugin's pipeline, contributed through the entry-point group ``spflow.pipelines`` (``pyproject.toml``)
and run by name from any directory once the package is installed:

    spflow run breakthrough_scan --quick
    spflow run breakthrough_scan --set breakthrough.fraction=0.3

``space`` (AD41 and CRK, ±30 % around the defaults) -> ``design`` (Latin hypercube) -> ``runs`` (the simulator on
BCF2) -> ``breakthrough`` (this package's stage). ``report`` writes ``breakthrough.nc`` and one line per sample.
"""

from pathlib import Path

import spflow


def pipeline(samples: int = 6, cells: int = 40, fraction: float = 0.5, quick: bool = False) -> spflow.Pipeline:
    """``quick``: two samples on a 20-cell grid."""
    if quick:
        samples, cells = 2, 20
    p = spflow.Pipeline("breakthrough_scan_quick" if quick else "breakthrough_scan")
    p.add("space", "parameter_space", params={"names": ["AD41", "CRK"], "relative": 0.3})
    p.add("design", "lhs_design", inputs={"space": "space"}, params={"samples": samples, "seed": 1})
    p.add("runs", "forward", inputs={"design": "design"}, params={"experiments": ["BCF2"], "cells": cells})
    p.add("breakthrough", "breakthrough", inputs={"responses": "runs"}, params={"fraction": fraction})
    return p


def report(result: spflow.RunResult, outdir: Path) -> list[str]:
    """``breakthrough.nc`` and, per sample, the breakthrough PV and the pressure-drop peak."""
    bt = result["breakthrough"]
    bt.to_netcdf(outdir / "breakthrough.nc")
    lines = [f"polymer breakthrough at {bt.attrs['fraction']:g} of the maximum effluent concentration, BCF2:"]
    for s in range(bt.sizes["sample"]):
        row = bt.isel(sample=s, experiment=0)
        lines.append(f"  sample {s}: {float(row['polymer_breakthrough_pv']):.3f} PV; dp peak "
                     f"{float(row['dp_peak']) / 1e3:.1f} kPa at {float(row['dp_peak_pv']):.2f} PV")
    return lines
