"""Prior spread of a study's corefloods (LHS of its calibrated space through the simulator) against their data.

Latin-hypercube samples of the study's calibrated parameter space (default: the bundled study, BCF1-3, whose space is
the Table 3.2 ranges with n_high / n_low moving every phase's Corey exponent; ``profile="thesis"``: thesis Table 3.2
as the chapter-3 pipeline's thesis profile uses it) are run through the forward model for every observed coreflood of
the study (training and held out), each with its own core, rate and schedule; the measured data enter through the
``observations`` stage (on the simulator's output grid, content-hashed). The report draws the P10-P90 band and median
of pressure drop, oil cut and cumulative recovery per experiment with the measurements on top (cf. thesis Figs.
2.11-2.13).

    spflow run prior_spread --jobs 2
    spflow run prior_spread --study study.toml
"""

from __future__ import annotations

from pathlib import Path

import spflow
from spflow.pipelines.history_matching import space_params
from spflow.plugins.design.thesis_tables import TABLE_3_2
from spflow.study.pipeline_inputs import StudyInputs


def pipeline(samples: int = 32, study=None, profile: str = "study") -> spflow.Pipeline:
    """The spread of ``study`` (a study file, a Study, or ``None``: the bundled study) under ``profile`` (``"study"``:
    its calibrated space; ``"thesis"``: Table 3.2, see ``history_matching``)."""
    inputs = StudyInputs.of(study)
    p = spflow.Pipeline("prior_spread")
    p.add("space", "parameter_space", params=space_params(inputs, profile, TABLE_3_2))
    p.add("design", "lhs_design", inputs={"space": "space"}, params={"samples": samples, "seed": 2024})
    p.add("responses", "forward", inputs={"design": "design"},
          params={"experiments": inputs.forward(inputs.observed), **inputs.model()})
    p.add("spread", "quantiles", inputs={"ensemble": "responses"}, params={"levels": [0.1, 0.5, 0.9]})
    p.add("observations", "observations", params={"experiments": inputs.observations(inputs.observed)})
    return p


def report(result: spflow.RunResult, outdir: Path) -> list[str]:
    """Write the spread figure and the quantile Dataset; return the lines to print."""
    from spflow.core.figure import subplots

    spread = result["spread"]
    spread.to_netcdf(outdir / "prior_spread.nc")
    qois = [("dp", 1e-3, "Δp (kPa)"), ("oil_cut", 1.0, "oil cut (–)"), ("recovery", 1.0, "recovery (fraction OOIP)")]
    experiments = [str(e) for e in spread["experiment"].values]
    fig, axes = subplots(len(qois), len(experiments), figsize=(4 * len(experiments), 8), sharex="col")
    for j, exp in enumerate(experiments):
        end = float(spread["total_pv"].sel(experiment=exp))
        sel = spread.sel(experiment=exp).sel(pv=slice(0, end)).dropna("pv", subset=["dp_mean"])
        for i, (name, scale, label) in enumerate(qois):
            ax = axes[i, j]
            lo, mid, hi = (sel[name].sel(quantile=q) * scale for q in (0.1, 0.5, 0.9))
            ax.fill_between(sel["pv"], lo, hi, alpha=0.3, label="P10–P90")
            ax.plot(sel["pv"], mid, lw=1.5, label="median")
            obs = result["observations"][name].sel(experiment=exp).dropna("pv")
            ax.plot(obs["pv"], obs * scale, ".", ms=3, color="k", label="measured")
            ax.set_ylabel(label)
            if i == 0:
                ax.set_title(exp)
            if i == len(qois) - 1:
                ax.set_xlabel("injected pore volumes (PV)")
    axes[0, 0].legend(loc="best")
    fig.suptitle(f"Prior spread, {spread.attrs['ensemble_size']} LHS samples of the calibrated space")
    fig.tight_layout()
    fig.savefig(outdir / "prior_spread.png", dpi=110)
    lines = [f"wrote {outdir / 'prior_spread.png'} and {outdir / 'prior_spread.nc'}"]
    for exp in experiments:
        final = spread["recovery"].sel(experiment=exp).sel(pv=float(spread["total_pv"].sel(experiment=exp)),
                                                             method="nearest")
        lines.append(f"{exp}: final recovery P10/P50/P90 = "
                     + " / ".join(f"{float(final.sel(quantile=q)):.3f}" for q in (0.1, 0.5, 0.9)))
    return lines
