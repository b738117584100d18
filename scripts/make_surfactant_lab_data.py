"""Generate the bundled synthetic surfactant lab tables (phase behaviour, IFT, ME viscosity, capillary desaturation).

Truth = the forward model's defaults (thesis Table 2.4) except S2RC = 0.05: the thesis's CDC (Fig. 2.8) levels off
near S_or ~ 0.1 at the highest rate, and a high-N_c residual inside its range (not on the bound 0) keeps the fit
regular. ME viscosity keeps Table 2.4's ALPHAV3 = 0, so only ALPHAV1, ALPHAV2 are identifiable (the stage default).
Writes ``spflow/datasets/lab/<kind>.csv`` and ``spflow/datasets/lab/surfactant_truth.toml``.

    .venv/bin/python scripts/make_surfactant_lab_data.py
"""

from __future__ import annotations


import numpy as np

from spflow.plugins.forward.parameters import default_params
from spflow.plugins.lab import desaturation_fit, ift_fit, me_viscosity_fit, phase_behaviour_fit
from spflow.plugins.lab.polymer_fit_stages import LAB_DIR, bundled_lab_path
from spflow.plugins.lab.lab_table import write_lab_table

TRUTH = {**default_params(), "S2RC": 0.05}

#: pipette salinity scan: 0.05-0.55 meq/ml every 0.05 plus the type III window every 0.005 (20 tubes), 0.678 %
#: surfactant at water/oil ratio 1 (thesis section 2.5)
PIPETTE_SALINITY = np.round(np.r_[np.arange(0.05, 0.551, 0.05), np.arange(0.26, 0.301, 0.005)], 4)
#: IFT: the same salinities (every 0.05) at five surfactant fractions down to twice the CMC
IFT_SALINITY = np.round(np.arange(0.05, 0.551, 0.05), 4)
IFT_SURFACTANT = (2e-4, 5e-4, 1e-3, 3e-3, 6.78e-3)
#: ME viscosity: oil fraction of the surfactant-free part x surfactant fraction
ME_OIL = np.round(np.linspace(0.05, 0.95, 10), 4)
ME_SURFACTANT = (0.02, 0.05, 0.1, 0.2, 0.3)
#: CDC: 16 capillary numbers, log-spaced 1e-7 ... 1e-1 (rate steps, then low-IFT floods)
CDC_NUMBER = np.geomspace(1e-7, 1e-1, 16)

NOISE = {"phase_behaviour": 0.05, "ift": 0.08, "me_viscosity": 0.04, "desaturation": 0.01}
NOISE_DOC = {
    "phase_behaviour": "multiplicative: ratio * exp(N(0, 0.05^2)) (~5 % pipette reading error)",
    "ift": "multiplicative: IFT * exp(N(0, 0.08^2)) (~8 % spinning-drop error)",
    "me_viscosity": "multiplicative: viscosity * exp(N(0, 0.04^2)) (~4 % rheometer error)",
    "desaturation": "additive: S_or + N(0, 0.01^2) (material-balance error 0.01 saturation)",
}
SEEDS = {"phase_behaviour": 101, "ift": 102, "me_viscosity": 103, "desaturation": 104}
FITTED = {
    "phase_behaviour": phase_behaviour_fit.NAMES,
    "ift": ift_fit.NAMES,
    "me_viscosity": ("ALPHAV1", "ALPHAV2"),
    "desaturation": desaturation_fit.phase_names(2),
}


def tables() -> dict[str, object]:
    """The four synthetic lab tables (Datasets in lab-table layout) with the bundled seeds and noise levels."""
    return {
        "phase_behaviour": phase_behaviour_fit.synthetic_pipette_tests(
            TRUTH, PIPETTE_SALINITY, noise=NOISE["phase_behaviour"], seed=SEEDS["phase_behaviour"],
            experiment="S13D pipette tests, 0.678 % surfactant, WOR 1 (synthetic)"),
        "ift": ift_fit.synthetic_ift_table(
            TRUTH, IFT_SALINITY, IFT_SURFACTANT, noise=NOISE["ift"], seed=SEEDS["ift"],
            experiment="spinning-drop IFT of the pipette scan (synthetic)"),
        "me_viscosity": me_viscosity_fit.synthetic_me_viscosity(
            TRUTH, ME_OIL, ME_SURFACTANT, noise=NOISE["me_viscosity"], seed=SEEDS["me_viscosity"],
            experiment="single-phase microemulsion viscosities (synthetic)"),
        "desaturation": desaturation_fit.synthetic_desaturation(
            TRUTH, CDC_NUMBER, phase=2, noise=NOISE["desaturation"], seed=SEEDS["desaturation"],
            experiment="Berea CDC, Table 2.3 core (synthetic)"),
    }


def main() -> None:
    truth_lines = ["# Truth of the bundled synthetic lab tables of scripts/make_surfactant_lab_data.py (tests only).",
                   "# Truth = spflow.plugins.forward.parameters defaults (thesis Table 2.4) except S2RC = 0.05.", ""]
    for kind, ds in tables().items():
        path = write_lab_table(ds, bundled_lab_path(kind), kind)
        print(f"wrote {path} ({ds.sizes['point']} points)")
        truth_lines += [f"[{kind}]", f'file = "{path.name}"', f"seed = {SEEDS[kind]}",
                        f"noise = {NOISE[kind]}", f'noise_model = "{NOISE_DOC[kind]}"', f"[{kind}.truth]"]
        truth_lines += [f"{name} = {TRUTH[name]!r}" for name in FITTED[kind]]
        truth_lines.append("")
    out = LAB_DIR / "surfactant_truth.toml"
    out.write_text("\n".join(truth_lines), encoding="utf-8")
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
