"""Regenerate the bundled synthetic lab tables of lab fits A (polymer rheology, polymer coreflood, adsorption,
tracer) in ``spflow/datasets/lab/`` and their truth in ``spflow/datasets/lab/polymer_truth.toml``.

Truth: thesis Table 2.4 (the forward model's defaults) for every fitted UTCHEM parameter; TDS_PER_EC (not in
Table 2.4) = 600 ppm per mS/cm, a typical NaCl-brine value. Noise levels and seeds are written to the truth file.

Usage: ``python scripts/make_polymer_lab_data.py``
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from spflow.plugins.forward.parameters import default_params
from spflow.plugins.lab import adsorption_fit, polymer_coreflood, polymer_rheology, tracer_fit
from spflow.plugins.lab.polymer_fit_stages import LAB_DIR
from spflow.plugins.lab.lab_table import write_lab_table

SEED = 20240610
NOISE = {"polymer_rheology": 0.02, "polymer_coreflood": 0.01, "adsorption": 0.04, "tracer": 0.01}
TDS_PER_EC = 600.0


def truth() -> dict[str, float]:
    d = default_params()
    names = (*polymer_rheology.NAMES, *polymer_coreflood.NAMES, "AD41", "AD42", "B4D", "AD31", "AD32", "B3D",
             "ALPHAL1")
    return {n: d[n] for n in names} | {"TDS_PER_EC": TDS_PER_EC}


def main(out: Path = LAB_DIR) -> None:
    out.mkdir(parents=True, exist_ok=True)
    t = truth()
    rng = np.random.default_rng(SEED)
    written = []
    ds = polymer_rheology.synthetic_rheology(t, rng, noise=NOISE["polymer_rheology"])
    written.append(write_lab_table(ds, out / "polymer_rheology.csv", polymer_rheology.KIND))
    ds = polymer_coreflood.synthetic_coreflood(t, rng, noise=NOISE["polymer_coreflood"])
    written.append(write_lab_table(ds, out / "polymer_coreflood.csv", polymer_coreflood.KIND))
    for component, (kind, _, _, _) in adsorption_fit.COMPONENTS.items():
        ds = adsorption_fit.synthetic_adsorption(component, t, rng, noise=NOISE["adsorption"])
        written.append(write_lab_table(ds, out / f"{kind}.csv", kind))
    effluent, calibration = tracer_fit.synthetic_tracer(t, rng, noise=NOISE["tracer"])
    written.append(write_lab_table(effluent, out / "tracer.csv", tracer_fit.KIND))
    written.append(write_lab_table(calibration, out / "conductivity_calibration.csv", tracer_fit.CALIBRATION_KIND))

    lines = [
        "# Truth of the bundled synthetic lab tables of lab fits A (scripts/make_polymer_lab_data.py).",
        "# Values: thesis Table 2.4 (forward-model defaults); TDS_PER_EC is a typical NaCl-brine value.",
        "# Generated in this order from one numpy default_rng(seed): rheology, coreflood, polymer adsorption,",
        "# surfactant adsorption, tracer effluent + calibration.",
        f"seed = {SEED}",
        "",
        "[truth]",
        *(f"{k} = {v!r}" for k, v in t.items()),
        "",
        "[noise]",
        f'polymer_rheology = "{NOISE["polymer_rheology"]:g} relative, log-normal, per viscosity reading"',
        f'polymer_coreflood = "{NOISE["polymer_coreflood"]:g} relative, log-normal, per pressure reading"',
        f'adsorption = "{NOISE["adsorption"]:g} x Langmuir plateau (mg/g), additive Gaussian"',
        f'tracer = "{NOISE["tracer"]:g} x mean brine conductivity, additive Gaussian"',
        "",
    ]
    (out / "polymer_truth.toml").write_text("\n".join(lines))
    for p in written:
        print(p)


if __name__ == "__main__":
    main()
