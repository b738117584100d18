"""Figure docs/figures/lab_like_vs_clean.png: a clean BCF1 simulation and its lab-like version.

The lab-like version is the same simulation seen through the default measurement model
(``spflow.synthetic.NoiseModel()``, seed 0): transducer noise/offset/drift on a 0.02 PV grid, 0.05 PV tubes
read to 0.1 ml, 2 ml of outlet dead volume, 3 % assay noise.

    .venv/bin/python scripts/make_lab_like_figure.py
"""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from spflow.io.format import schedule_json  # noqa: E402
from spflow.plugins.forward.simulate import simulate  # noqa: E402
from spflow.synthetic import NoiseModel, measure  # noqa: E402

OUT = Path(__file__).resolve().parents[1] / "docs" / "figures" / "lab_like_vs_clean.png"


def main() -> None:
    clean = simulate("BCF1", pv_step=0.005)
    lab = measure(clean, NoiseModel(), 0, experiment="BCF1", source="figure", schedule=schedule_json("BCF1"))
    fig, axes = plt.subplots(2, 2, figsize=(11, 7), sharex=True)
    panels = [("dp", 1e-3, "pressure drop (kPa)", "pv"), ("oil_cut", 1.0, "oil cut (-)", "pv_tube"),
              ("recovery", 1.0, "recovery (fraction OOIP)", "pv_tube_end"),
              ("c_polymer_out", 1.0, "effluent polymer (ppm)", "pv_tube")]
    for ax, (name, scale, label, coord) in zip(axes.flat, panels):
        ax.plot(clean["pv"], clean[name] * scale, color="k", lw=1.2, label="clean simulation")
        style = dict(ls="-", marker=".", ms=3, lw=0.6) if name == "dp" else dict(ls="none", marker="o", ms=3)
        ax.plot(lab[coord], lab[name] * scale, color="tab:red", label="lab-like (default NoiseModel)", **style)
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
    for ax in axes[1]:
        ax.set_xlabel("injected pore volumes (PV)")
    axes[0, 0].legend(loc="upper left", fontsize=8)
    fig.suptitle("BCF1 (default parameters): clean simulation vs its lab-like measurement")
    fig.tight_layout()
    OUT.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(OUT, dpi=130)
    print(f"wrote {OUT}")


if __name__ == "__main__":
    main()
