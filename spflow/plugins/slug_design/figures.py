"""Figures of the slug-size design (thesis Figs. 4.6-4.10), drawn with matplotlib (Agg) from ``slug_design`` outputs.

* :func:`plot_price_paths` — Fig. 4.6: sample paths of the stochastic oil price (Eq. 4.12), one panel per drift.
* :func:`plot_front_evolution` — Figs. 4.7-4.8: the projected Pareto front (NPV to maximise against max Δp to
  minimise, so the best designs lie bottom right) after the kept iterations: every evaluated design (GP mean), the
  front as a staircase of diamonds, the design the algorithm picks next (red), the front uncertainty of that
  iteration's GPs (empirical attainment function of the sampled fronts in grey levels, Vorob'ev expectation) and, in
  the last panel, the knee design.
* :func:`plot_knee_design` — Figs. 4.9-4.10: the knee design's schedule (injected salinity, surfactant and polymer
  against PV) and its pressure drop, oil cut and recovery over the posterior draws (median and 5-95 % band), with the
  distribution of its NPV over draws and price paths in the title.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import numpy as np
import xarray as xr

from spflow.core.figure import subplots

from .slug_schedule import REFERENCE, SlugReference, slug_schedule

__all__ = ["plot_price_paths", "plot_front_evolution", "plot_knee_design"]


def plot_price_paths(results: Mapping[str, xr.Dataset], path: str | Path) -> Path:
    """Fig. 4.6: the stored price paths of each result (e.g. {"positive drift": ..., "negative drift": ...})."""
    fig, axes = subplots(1, len(results), figsize=(5.2 * len(results), 3.8), sharey=True, squeeze=False)
    for ax, (label, ds) in zip(axes[0], results.items()):
        t = ds["time"].values
        for row in ds["price_path"].values:
            ax.plot(t, row, lw=0.6, alpha=0.7)
        mu, n = ds.attrs["drift"], ds.attrs["steps_per_year"]
        ax.plot(t, ds.attrs["initial_price"] * np.exp(mu * n * t), "k--", lw=1.2, label="S0 exp(μ t) (median)")
        ax.set_title(f"{label}: μ = {mu:+.0e}/step, α = {ds.attrs['volatility']:.0e}/√step, {n} steps/year",
                     fontsize=9)
        ax.set_xlabel("time (years)")
        ax.legend(fontsize=8, loc="upper left")
    axes[0, 0].set_ylabel("oil price S(t) (\\$/bbl)")
    fig.suptitle("Fig. 4.6: samples of the stochastic oil price model (Eq. 4.12)")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    return Path(path)


def _staircase(front: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Attainment staircase of a minimisation front (k, 2) sorted by the first objective, in (NPV, Δp) coordinates."""
    f = front[np.argsort(front[:, 0])]
    x = np.repeat(f[:, 0], 2)[1:]
    y = np.repeat(f[:, 1], 2)[:-1]
    return -x, y


def _npv_dp(values: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    return -values[..., 0], values[..., 1]


def _dominated_polygon(front: np.ndarray, reference: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Boundary of the region a minimisation front (k, 2) dominates up to ``reference``, in (NPV, Δp) coordinates."""
    f = front[np.argsort(front[:, 0])]
    f = np.minimum(f, reference)
    x = np.concatenate([[f[0, 0]], np.repeat(f[:, 0], 2)[1:], [reference[0], reference[0]]])
    y = np.concatenate([[reference[1]], np.repeat(f[:, 1], 2)[:-1], [f[-1, 1], reference[1]]])
    return -x, y


def _uncertainty_layer(ax, ds: xr.Dataset, snapshot: int, n_levels: int = 10) -> None:
    """EAF of the sampled fronts of one snapshot, shaded where a Pareto-optimal point may still lie: the regions
    attained by at least 10 %, 20 %, ..., 90 % of the fronts overlaid in translucent grey (darker = attained by more
    fronts), minus the region every sampled front attains; and the Vorob'ev expectation."""
    here = ds["eaf_snapshot"].values == snapshot
    points, levels = ds["eaf_objectives"].values[here], ds["eaf_level"].values[here]
    available = np.unique(levels)
    reference = ds["reference"].values
    for target in np.linspace(100.0 / n_levels, 100.0, n_levels)[:-1]:
        above = available[available >= target - 1e-9]
        if above.size and above.min() < available.max():
            x, y = _dominated_polygon(points[levels == above.min()], reference)
            ax.fill(x, y, color="0.25", alpha=0.7 / n_levels, lw=0)
    x, y = _dominated_polygon(points[levels == available.max()], reference)
    ax.fill(x, y, color="white", lw=0)
    vorob = ds["vorob_expectation"].values[ds["vorob_snapshot"].values == snapshot]
    x, y = _staircase(vorob)
    threshold = float(ds["vorob_threshold"].sel(snapshot=snapshot))
    ax.plot(x, y, color="tab:blue", lw=1.0, ls="--", label=f"Vorob'ev expectation (β* = {threshold:.0f} %)")


def plot_front_evolution(ds: xr.Dataset, path: str | Path, title: str) -> Path:
    """Figs. 4.7-4.8: projected fronts after the kept iterations and, last, the final front with its uncertainty."""
    snaps = ds["snapshot"].values
    fig, axes = subplots(1, len(snaps), figsize=(4.6 * len(snaps), 4.2), squeeze=False)
    chosen = ds["chosen_at"].values
    for ax, k in zip(axes[0], snaps):
        proj = ds["snapshot_projected"].sel(snapshot=k).values
        seen = np.isfinite(proj[:, 0])
        front = proj[ds["snapshot_on_front"].sel(snapshot=k).values]
        _uncertainty_layer(ax, ds, k)
        x, y = _npv_dp(proj[seen])
        ax.plot(x, y, "o", ms=3, color="0.45", label="evaluated designs (GP mean)")
        sx, sy = _staircase(front)
        ax.plot(sx, sy, "-", color="tab:green", lw=1.2)
        fx, fy = _npv_dp(front)
        ax.plot(fx, fy, "D", ms=5, color="tab:green", label=f"projected front ({len(front)})")
        nxt = np.flatnonzero(chosen == k + 1)
        if nxt.size:
            px, py = _npv_dp(ds["observed"].values[nxt])
            ax.plot(px, py, "o", ms=7, color="red", label="next design (observed)")
        if k == snaps[-1]:
            kx, ky = _npv_dp(ds["knee_projected"].values)
            ax.plot(kx, ky, "*", ms=14, color="gold", mec="k", label="knee (TMDSM)")
        ax.set_title(f"N_itr = {int(k)}; Vorob'ev deviation "
                     f"{float(ds['vorob_deviation'].sel(snapshot=k)):.3g} M\\$·kPa", fontsize=9)
        ax.set_xlabel("E[NPV] (M\\$)")
        ax.set_ylabel("E[max Δp] (kPa)")
        ax.legend(fontsize=7, loc="upper left", framealpha=0.8)
    fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    return Path(path)


def _band(ax, pv, values, color, label):
    lo, mid, hi = np.nanquantile(values, [0.05, 0.5, 0.95], axis=0)
    ax.fill_between(pv, lo, hi, color=color, alpha=0.3, lw=0, label="5-95 % over draws")
    ax.plot(pv, mid, color=color, lw=1.4, label=f"median {label}")


def plot_knee_design(ds: xr.Dataset, path: str | Path, title: str) -> Path:
    """Figs. 4.9-4.10: schedule and responses of the knee design over the posterior draws."""
    x = ds["knee_design"].values
    reference = SlugReference.from_json(ds.attrs["reference_flood"]) if "reference_flood" in ds.attrs else REFERENCE
    sched = slug_schedule(*x, total_pv=ds.attrs["total_pv"], reference=reference)
    fig, axes = subplots(2, 2, figsize=(10, 7))
    ax = axes[0, 0]
    edges = np.concatenate([[0.0], np.cumsum([s.pv for s in sched.slugs])])
    for field, color, label in (("salinity_ppm", "tab:gray", "salinity (TDS)"),
                                ("surfactant_ppm", "tab:orange", "surfactant"),
                                ("polymer_ppm", "tab:purple", "polymer")):
        values = [getattr(s, field) for s in sched.slugs]
        ax.stairs(values, edges, color=color, lw=1.6, label=label)
    for s, a, b in zip(sched.slugs, edges[:-1], edges[1:]):
        if b - a >= 0.3:  # narrow slugs are named in the title
            ax.text(0.5 * (a + b), ax.get_ylim()[1] * 0.92, s.name, ha="center", fontsize=8)
    start, rate = ds.attrs["project_start_pv"], ds.attrs["injection_rate_pv_per_year"]
    ax.axvline(start, color="k", lw=0.8, ls=":")
    years = ax.secondary_xaxis("top", functions=(lambda pv: (pv - start) / rate, lambda t: start + rate * t))
    years.set_xlabel("project year (scale-up)", fontsize=8)
    ax.set_xlabel("injected PV")
    ax.set_ylabel("injected concentration (ppm)")
    ax.set_title("schedule: " + ", ".join(f"{n} = {v:.2f} PV" for n, v in zip(ds["design_var"].values, x)),
                 fontsize=9)
    ax.legend(fontsize=7, loc="center right")
    pv = ds["pv"].values
    for ax, (name, color, label) in zip(
            (axes[0, 1], axes[1, 0], axes[1, 1]),
            (("knee_dp", "tab:red", "pressure drop (kPa)"), ("knee_oil_cut", "tab:brown", "oil cut (-)"),
             ("knee_recovery", "tab:blue", "recovery (fraction OOIP)"))):
        _band(ax, pv, ds[name].values, color, label.split(" (")[0])
        ax.set_xlabel("injected PV")
        ax.set_ylabel(label)
        ax.legend(fontsize=7)
    npv = ds["knee_npv"].values
    fig.suptitle(f"{title}\nNPV over {npv.size} draws: median {np.median(npv):.3f} M\\$, 5-95 % "
                 f"[{np.quantile(npv, 0.05):.3f}, {np.quantile(npv, 0.95):.3f}] M\\$; max Δp median "
                 f"{np.median(ds['knee_max_dp'].values):.1f} kPa", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    return Path(path)
