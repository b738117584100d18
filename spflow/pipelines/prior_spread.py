"""Prior spread of BCF1–3 (LHS of the Table 3.2 space through the simulator) against the bundled data.

Latin-hypercube samples of the thesis's reduced parameter space (Table 3.2 ranges) are run through the forward model
for the three bundled injection schedules (Table 2.5); the bundled lab-like measurements enter through content-hashed
``load_netcdf`` nodes. The report draws the P10–P90 band and median of pressure drop, oil cut and cumulative recovery
per experiment with the measurements on top (cf. thesis Figs. 2.11–2.13).

    spflow run prior_spread --jobs 2
"""

from __future__ import annotations

from pathlib import Path

import spflow
from spflow import datasets
from spflow.plugins.design.thesis_tables import TABLE_3_2

def pipeline(samples: int = 32) -> spflow.Pipeline:
    p = spflow.Pipeline("prior_spread")
    p.add("space", "parameter_space", params={"names": list(TABLE_3_2), "ranges": TABLE_3_2})
    p.add("design", "lhs_design", inputs={"space": "space"}, params={"samples": samples, "seed": 2024})
    p.add("responses", "forward", inputs={"design": "design"}, params={"experiments": ["BCF1", "BCF2", "BCF3"]})
    p.add("spread", "quantiles", inputs={"ensemble": "responses"}, params={"levels": [0.1, 0.5, 0.9]})
    for name in datasets.names():
        p.add(f"observed_{name}", "load_netcdf", params={"path": str(datasets.path(name))})
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
            obs = result[f"observed_{exp}"][name]
            ax.plot(obs[obs.dims[0]], obs * scale, ".", ms=3, color="k", label="bundled data")
            ax.set_ylabel(label)
            if i == 0:
                ax.set_title(exp)
            if i == len(qois) - 1:
                ax.set_xlabel("injected pore volumes (PV)")
    axes[0, 0].legend(loc="best")
    fig.suptitle(f"Prior spread, {spread.attrs['ensemble_size']} LHS samples of the Table 3.2 space")
    fig.tight_layout()
    fig.savefig(outdir / "prior_spread.png", dpi=110)
    lines = [f"wrote {outdir / 'prior_spread.png'} and {outdir / 'prior_spread.nc'}"]
    for exp in experiments:
        final = spread["recovery"].sel(experiment=exp).sel(pv=float(spread["total_pv"].sel(experiment=exp)),
                                                             method="nearest")
        lines.append(f"{exp}: final recovery P10/P50/P90 = "
                     + " / ".join(f"{float(final.sel(quantile=q)):.3f}" for q in (0.1, 0.5, 0.9)))
    return lines
