"""OPM Flow beside spflow on one coreflood: both in the coreflood format, a comparison table and a figure.

:func:`compare_opm` exports the deck, runs OPM Flow and spflow (same cells; spflow's scheme selectable, first-order
``upwind`` for a like-for-like comparison), and turns spflow's run into the coreflood format with tubes of OPM's
report step (spflow's own measurement chain with no noise and no dead volume), so the two files can be read and
plotted like observations. :func:`comparison_table` gives the numbers the project's acceptance uses: recovery at
the end, the largest recovery difference, the polymer effluent midpoint (half the largest injected
concentration), and the pressure drop at the end of every slug.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import xarray as xr

from spflow.io.format import schedule_json
from spflow.plugins.forward.simulate import simulate
from spflow.synthetic.measurement import measure
from spflow.synthetic.noise_model import NoiseModel

from .opm_deck import write_opm_deck
from .opm_run import run_opm

__all__ = ["compare_opm", "comparison_table", "spflow_coreflood", "plot_comparison"]


def spflow_coreflood(sched, params, effects, *, cells: int, scheme: str, pv_step: float) -> xr.Dataset:
    """spflow's run of ``sched`` in the coreflood format: pressure every ``pv_step``, tubes of ``pv_step``, exact."""
    clean = simulate(sched, params, cells=cells, effects=effects, scheme=scheme, pv_step=pv_step)
    noise = NoiseModel.exact(tube_pv=pv_step, pressure_interval_pv=pv_step)
    return measure(clean, noise, 0, experiment=sched.name, source=f"spflow simulate (scheme {scheme}, {cells} cells)",
                   schedule=schedule_json(sched), empty_tubes="limit")


def _midpoint(ds: xr.Dataset, half: float) -> float:
    if "c_polymer_out" not in ds:
        return float("nan")
    c = np.nan_to_num(ds["c_polymer_out"].values)
    above = np.flatnonzero(c >= half)
    if above.size == 0 or above[0] == 0:
        return float("nan")
    i = int(above[0])
    x = ds["pv_tube"].values
    return float(x[i - 1] + (half - c[i - 1]) / (c[i] - c[i - 1]) * (x[i] - x[i - 1]))


def _dp_at_slug_end(ds: xr.Dataset, end: float) -> float:
    """Δp at the end of a slug: its left limit, from the samples up to ``end`` (OPM's report point there is rounded
    to whole seconds, so samples within a quarter of the median spacing, at most 1e-3 PV, after ``end`` count as at
    it). After a rate step the next sample already holds the next slug's Δp, which interpolating across would mix
    in."""
    pv, dp = ds["pv"].values, ds["dp"].values
    tol = min(1.0e-3, 0.25 * float(np.median(np.diff(pv))))
    keep = pv <= end + tol
    return float(np.interp(end, pv[keep], dp[keep]))


def comparison_table(opm: xr.Dataset, ref: xr.Dataset, sched) -> list[dict]:
    """Rows ``{"quantity", "unit", "opm", "spflow", "difference"}`` (difference OPM - spflow; relative for Δp)."""
    rows = []

    def row(q, unit, a, b, relative=False):
        diff = (a / b - 1.0) if relative and b != 0.0 else a - b
        rows.append({"quantity": q, "unit": unit, "opm": a, "spflow": b,
                     "difference": diff, "difference_unit": "relative" if relative else unit})

    row("recovery at the end", "1", float(opm["recovery"].values[-1]), float(ref["recovery"].values[-1]))
    rec_ref = np.interp(opm["pv_tube_end"].values, ref["pv_tube_end"].values, ref["recovery"].values)
    worst = int(np.argmax(np.abs(opm["recovery"].values - rec_ref)))
    row(f"largest recovery difference (at {opm['pv_tube_end'].values[worst]:.3f} PV)", "1",
        float(opm["recovery"].values[worst]), float(rec_ref[worst]))
    top = max(s.polymer_ppm for s in sched.slugs)
    if top > 0.0:
        half = 0.5 * top
        row(f"polymer effluent midpoint ({half:g} ppm)", "PV", _midpoint(opm, half), _midpoint(ref, half))
    end = 0.0
    for slug in sched.slugs:
        end += slug.pv
        row(f"dp at the end of slug {slug.name!r} ({end:.3g} PV)", "Pa", _dp_at_slug_end(opm, end),
            _dp_at_slug_end(ref, end), True)
    return rows


def plot_comparison(opm: xr.Dataset, ref: xr.Dataset, path, title: str = "") -> Path:
    """Four panels (Δp, oil cut, recovery, effluent polymer) of OPM Flow and spflow; written to ``path``."""
    from spflow.core.figure import subplots

    fig, axes = subplots(2, 2, figsize=(10, 7), sharex=True)
    panels = (("dp", "pv", "Δp (kPa)", 1e-3), ("oil_cut", "pv_tube", "oil cut", 1.0),
              ("recovery", "pv_tube_end", "recovery (fraction of OOIP)", 1.0),
              ("c_polymer_out", "pv_tube", "effluent polymer (ppm)", 1.0))
    for ax, (var, coord, label, scale) in zip(axes.flat, panels):
        for ds, name, style in ((ref, "spflow", "-"), (opm, "OPM Flow", "--")):
            if var in ds:
                ax.plot(ds[coord].values, ds[var].values * scale, style, label=name)
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
    for ax in axes[1]:
        ax.set_xlabel("injected PV")
    axes[0, 0].legend()
    fig.suptitle(title or "spflow vs OPM Flow")
    fig.tight_layout()
    path = Path(path)
    fig.savefig(path, dpi=120)
    return path


def compare_opm(schedule, params=None, effects=None, *, cells: int = 100, scheme: str = "upwind",
                pv_step: float = 0.01, out=None, approximate: bool = False, log=print, **deck_options):
    """Export, run OPM Flow and spflow, and compare. Returns ``(opm, spflow, rows)`` (coreflood Datasets and the
    :func:`comparison_table` rows); with ``out`` (a directory) also writes the deck, ``opm.nc``, ``spflow.nc``,
    ``comparison.csv`` and ``comparison.png`` there."""
    out_dir = Path(out) if out is not None else None
    deck_dir = out_dir if out_dir is not None else Path.cwd() / "opm_deck"
    deck = write_opm_deck(deck_dir / "CORE.DATA", schedule, params, effects, cells, approximate=approximate,
                          pv_step=pv_step, log=log, **deck_options)
    opm = run_opm(deck, None if out_dir is None else out_dir / "opm_run")
    sched = deck.schedule
    ref = spflow_coreflood(sched, params, effects, cells=cells, scheme=scheme, pv_step=pv_step)
    rows = comparison_table(opm, ref, sched)
    if out_dir is not None:
        opm.to_netcdf(out_dir / "opm.nc")
        ref.to_netcdf(out_dir / "spflow.nc")
        lines = ["quantity,unit,opm,spflow,difference,difference_unit"]
        lines += [f"\"{r['quantity']}\",{r['unit']},{r['opm']:.6g},{r['spflow']:.6g},{r['difference']:.6g},"
                  f"{r['difference_unit']}" for r in rows]
        (out_dir / "comparison.csv").write_text("\n".join(lines) + "\n")
        plot_comparison(opm, ref, out_dir / "comparison.png", f"{sched.name}: spflow ({scheme}) vs OPM Flow, "
                        f"{cells} cells")
    return opm, ref, rows
