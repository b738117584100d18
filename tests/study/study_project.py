"""A small valid study in a directory (hand-written CSV coreflood, inline schedule), for the study tests.

The coreflood is typed by hand (no simulation): 3.0 PV at 0.25 PV spacing, dp in psi, core data in the header
(length in the format's unit, diameter with units, rate under its alias), no measurement chain.
"""

from pathlib import Path

ROWS = [(0.25 * k, 2.0 + 0.1 * k, max(0.6 - 0.05 * k, 0.0), min(0.05 * k, 1.0)) for k in range(1, 13)]


def data_text(header=None, rows=ROWS) -> str:
    """CSV text of the coreflood; ``header`` replaces the default header lines."""
    if header is None:
        header = ["# experiment: core7", "# core_length_m: 0.30", "# core_diameter: 1.5 in", "# porosity: 0.19",
                  "# swi: 0.28", "# rate_ml_min: 0.5", "# units: dp=psi"]
    lines = list(header) + ["pv,dp,oil_cut,recovery"]
    lines += [f"{pv:g},{dp:g},{cut:g},{rec:g}" for pv, dp, cut, rec in rows]
    return "\n".join(lines) + "\n"


STUDY = '''version = 1

[parameters.calibrated]
HBNC71 = [0.01, 0.02]
n_high = { names = ["E1C", "E2C", "E3C"], range = [1.5, 3.0] }

[parameters.fixed]
VIS2 = 13.8

[effects]
capillary_pressure = 0.0

[[experiment]]
name = "core7"
role = "calibration"
data = "core7.csv"
rate = "0.5 ml/min"
schedule = [
  { name = "WF", pv = 1.2, salinity_ppm = 9400 },
  { name = "P", pv = 0.8, salinity_ppm = 9400, polymer_ppm = 1500 },
  { name = "CW", pv = 1.0, salinity_ppm = 9400 },
]
[experiment.core]
length = "30 cm"
permeability = "350 mD"
[experiment.fluids]
VIS1 = "1.0 cP"
[experiment.measurement]
dead_volume_ml = 0.5
'''


def write_project(directory: Path, study: str = STUDY, data: str | None = None) -> Path:
    """Write ``study.toml`` and ``core7.csv`` into ``directory``; returns the study path."""
    (directory / "core7.csv").write_text(data_text() if data is None else data)
    path = directory / "study.toml"
    path.write_text(study)
    return path
