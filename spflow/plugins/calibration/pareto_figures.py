"""Figures of the NSGA-II history match (thesis Figs. 3.10-3.14), drawn with matplotlib (Agg) from stage outputs.

* :func:`plot_fronts` — Fig. 3.10: the Pareto front (misfit of recovery vs misfit of pressure drop, Eq. 3.16) at the
  stored generations, plus the history: the part of the hypervolume reference box that the front does not
  dominate (1.1^k minus the normalised hypervolume, log scale, falls as the front advances) and σ_loss at the
  checkpoints.
* :func:`plot_history_match` — Figs. 3.11-3.13: for one coreflood, pressure drop, cumulative recovery and oil cut of
  the simulator at every Pareto point after the first and after the last generation (shaded min-max envelopes and
  thin lines) against the measured data.
* :func:`plot_parameter_ranges` — Fig. 3.14: each parameter's prior range (light), calibrated range (min-max of
  the final Pareto set, blue) and noise-consistent range (the likelihood-ratio region of
  :mod:`~spflow.plugins.calibration.nsga2_confidence`, orange), on the prior range scaled to [0, 1]; optionally a
  known truth (synthetic twins).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import xarray as xr
from matplotlib import colormaps

from spflow.core.figure import subplots
from spflow.plugins.calibration.nsga2_history import HV_REFERENCE

__all__ = ["plot_fronts", "plot_history_match", "plot_parameter_ranges"]

_QOIS = (("dp", 1e-3, "pressure drop (kPa)"), ("recovery", 1.0, "cumulative recovery (fraction OOIP)"),
         ("oil_cut", 1.0, "oil cut (-)"))


def _label(calibration: xr.Dataset, k: int) -> str:
    name = str(calibration["objective"].values[k])
    unit = str(calibration["objective_unit"].values[k])
    return f"½‖P − y‖² of {name}" + ("" if unit == "1" else f" ({unit})")


def plot_fronts(calibration: xr.Dataset, path: str | Path) -> Path:
    """Fig. 3.10 (fronts at the snapshot generations, log axes) and the run's history; returns the PNG path."""
    from matplotlib import ticker

    fig, (ax, hx) = subplots(1, 2, figsize=(11, 4.4), gridspec_kw={"width_ratios": [1.3, 1]})
    snaps = calibration["snapshot"].values
    colors = colormaps["viridis"](np.linspace(0.0, 0.9, len(snaps)))
    for color, g in zip(colors, snaps):
        f = calibration["front_objectives"].sel(snapshot=g).dropna("member").values
        f = f[np.argsort(f[:, 0])]
        ax.plot(f[:, 0], f[:, 1], "o-", ms=3, lw=0.8, color=color, label=f"N_gen = {int(g)} ({len(f)} points)")
    ax.set_xscale("log")
    ax.set_yscale("log")
    for axis in (ax.xaxis, ax.yaxis):  # labelled ticks at 1, 2, 5 x 10^k: readable when a front spans < 1 decade
        axis.set_major_locator(ticker.LogLocator(base=10, subs=(1.0, 2.0, 5.0)))
        axis.set_major_formatter(ticker.LogFormatterSciNotation(labelOnlyBase=False))
        axis.set_minor_formatter(ticker.NullFormatter())
    ax.set_xlabel(_label(calibration, 0))
    ax.set_ylabel(_label(calibration, 1))
    ax.set_title(f"Pareto front, training coreflood {calibration.attrs['training']}")
    ax.legend(fontsize=8)
    gen = calibration["generation"].values
    box = HV_REFERENCE ** calibration.sizes["objective"]  # hypervolume of the whole reference box
    hx.semilogy(gen, box - calibration["hypervolume"].values, color="C0")
    hx.set_xlabel("generation")
    hx.set_ylabel("reference box not dominated by the front", color="C0")
    sx = hx.twinx()
    sigma = calibration["sigma_loss"].values
    sx.plot(calibration["checkpoint"].values, sigma, "s", color="C3")
    sx.set_ylabel("σ_loss on held-out corefloods (simulator)", color="C3")
    sx.set_ylim(0.0, 1.25 * float(sigma.max()))
    hx.set_title("history")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    return Path(path)


def _series(responses: xr.Dataset, variable: str, experiment: str) -> xr.DataArray:
    end = float(responses["total_pv"].sel(experiment=experiment))
    da = responses[variable].sel(experiment=experiment)
    return da.sel(pv=da["pv"] <= end + 1e-9).dropna("pv", how="all")


def plot_history_match(responses: xr.Dataset, design: xr.Dataset, observations: xr.Dataset, experiment: str,
                       path: str | Path) -> Path:
    """Figs. 3.11-3.13 for ``experiment``: simulator ``responses`` (forward stage, dims sample, experiment, pv) at the
    Pareto sets of a ``pareto_design`` ``design`` (its ``generation`` coordinate splits the samples; the first
    generation is drawn green, the last red) over the data; returns the PNG path."""
    generation = design["generation"].values
    fig, axes = subplots(1, len(_QOIS), figsize=(14, 4))
    for ax, (name, scale, label) in zip(axes, _QOIS):
        for g, color in ((generation.min(), "tab:green"), (generation.max(), "tab:red")):
            da = _series(responses.isel(sample=np.flatnonzero(generation == g)), name, experiment) * scale
            ax.fill_between(da["pv"], da.min("sample"), da.max("sample"), color=color, alpha=0.25, lw=0,
                            label=f"Pareto set after N_gen = {g} ({da.sizes['sample']} runs)")
            ax.plot(da["pv"], da.transpose("pv", "sample"), color=color, lw=0.3, alpha=0.5)
        if name in observations:
            obs = observations[name].sel(experiment=experiment).dropna("pv") * scale
            ax.plot(obs["pv"], obs, "k.", ms=4, label="measured")
        ax.set_xlabel("injected pore volumes (PV)")
        ax.set_ylabel(label)
    axes[0].legend(fontsize=8, loc="best")
    fig.suptitle(f"{experiment}: simulator at the Pareto set vs data")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    return Path(path)


def plot_parameter_ranges(calibration: xr.Dataset, path: str | Path, truth: dict[str, float] | None = None) -> Path:
    """Fig. 3.14: prior, calibrated (Pareto) and noise-consistent range of each parameter on the prior scaled to
    [0, 1]; returns the PNG path."""
    names = [str(n) for n in calibration["param"].values]
    lo, hi = calibration["prior_lower"].values, calibration["prior_upper"].values
    fig, ax = subplots(figsize=(8, 0.55 * len(names) + 1.7))
    y = np.arange(len(names))[::-1]
    ax.barh(y, np.ones(len(names)), left=0.0, height=0.8, color="tab:blue", alpha=0.15, label="prior (Table 3.2)")
    level = calibration.attrs["confidence_level"]
    for kind, offset, color, label in (
            ("calibrated", 0.18, "tab:blue", "calibrated (final Pareto set)"),
            ("confidence", -0.18, "tab:orange", f"noise-consistent ({level:.0%} likelihood-ratio region)")):
        a, b = ((calibration[f"{kind}_{end}"].values - lo) / (hi - lo) for end in ("lower", "upper"))
        ax.barh(y + offset, np.maximum(b - a, 0.004), left=a, height=0.32, color=color, label=label)
    if truth is not None:
        t = np.array([(truth[n] - a) / (b - a) for n, a, b in zip(names, lo, hi)])
        ax.plot(t, y, "r|", ms=16, mew=2, label="truth")
    units = calibration["param_unit"].values
    ax.set_yticks(y, [f"{n} [{a:.3g}, {b:.3g}] {u}" for n, a, b, u in zip(names, lo, hi, units)], fontsize=8)
    ax.set_xlim(-0.02, 1.02)
    ax.set_xlabel("position in the prior range (0 = lower, 1 = upper bound)")
    ax.set_title("parameter ranges before and after calibration")
    ax.legend(fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.1), ncol=2)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    return Path(path)
