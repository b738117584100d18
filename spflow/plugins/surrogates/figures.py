"""Figures of the surrogate chapter (thesis §3.5-3.8), drawn with matplotlib (Agg) from the registered stages' outputs.

Each function writes one PNG and returns its path; the plotted numbers come from :mod:`.figure_data`.

* :func:`convergence_figure` -- Fig. 3.3: ε_LOO^mean and ε_emp^mean (Eqs. 3.9-3.10) against N_s, from the
  ``adaptive_pce`` output or from fits on growing designs.
* :func:`proxy_vs_simulator_figure` -- Figs. 3.4-3.5: proxy vs simulator on an independent validation design
  (``forward`` stage output), every PV step pooled plus the thesis's scalar QoIs (max Δp, final value).
* :func:`moments_figure` -- Figs. 3.7-3.9: the proxy's mean and standard deviation over PV against the runs' sample
  moments, with the relative L2 errors (Eq. 3.15).
* :func:`band_figure` -- Fig. 3.15: mean ± 2σ of any surrogate over PV for a few validation points with the simulator.

A surrogate argument is one surrogate Dataset or a mapping label -> Dataset (drawn side by side or overlaid).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np
import xarray as xr

from spflow.core.figure import subplots
from spflow.plugins.forward.schedule import as_schedule

from .figure_data import band_data, error_history, moment_data, scatter_data

__all__ = ["convergence_figure", "proxy_vs_simulator_figure", "moments_figure", "band_figure", "surrogate_label"]

#: (variable, stored unit) -> display scale, name and unit (others: the variable's name in its stored unit).
_DISPLAY = {("dp", "Pa"): (1e-3, "Δp", "kPa"), ("recovery", "1"): (1.0, "recovery", "fraction OOIP")}
#: Scalar QoI of each variable in Figs. 3.4-3.5 (max Δp; the final value of anything else).
_SCALAR = {"dp": "max"}


def _axis(variable: str, unit: str) -> tuple[float, str]:
    """(scale, axis label with unit) of a response variable stored in ``unit``."""
    if (variable, unit) in _DISPLAY:
        scale, name, shown = _DISPLAY[variable, unit]
        return scale, f"{name} ({shown})"
    return 1.0, f"{variable.replace('_', ' ')} ({'fraction' if unit == '1' else unit})"


def surrogate_label(surrogate: xr.Dataset) -> str:
    """E.g. ``"PCE (lars, N_s = 200)"``: the kind, a PCE's solver and the training size."""
    attrs = surrogate.attrs
    n = attrs.get("n_train", surrogate.sizes.get("train"))
    details = [str(attrs["solver"])] if "solver" in attrs else []
    details += [f"N_s = {n}"] if n is not None else []
    return f"{str(attrs['surrogate']).upper()}" + (f" ({', '.join(details)})" if details else "")


def _labelled(surrogate: xr.Dataset | Mapping[str, xr.Dataset]) -> dict[str, xr.Dataset]:
    return {surrogate_label(surrogate): surrogate} if isinstance(surrogate, xr.Dataset) else dict(surrogate)


def _save(fig, path: str | Path) -> Path:
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    return path


def convergence_figure(history: xr.Dataset | Mapping[str, xr.Dataset | Sequence[xr.Dataset]],
                       path: str | Path) -> Path:
    """Fig. 3.3: ε_LOO^mean (circles) and ε_emp^mean (squares) against N_s, one panel per variable, the selected
    degree p written by each LOO point. ``history`` is an ``adaptive_pce`` output, or a mapping label -> (an
    ``adaptive_pce`` output, surrogate fits on growing designs, or their :func:`.figure_data.error_history`)."""
    if isinstance(history, xr.Dataset):
        history = {"adaptive_pce": history}
    histories = {label: error_history(h) for label, h in history.items()}
    variables = list(dict.fromkeys(str(v) for h in histories.values() for v in h["variable"].values))
    fig, axes = subplots(1, len(variables), figsize=(max(6.5, 5 * len(variables)), 3.9), sharey=True, squeeze=False)
    for ax, v in zip(axes[0], variables):
        for (label, h), style in zip(histories.items(), ("-", "--", ":", "-.")):
            if v not in h["variable"].values:
                continue
            n_s, loo = h["n_s"].values, h["loo"].sel(variable=v).values
            ax.semilogy(n_s, loo, "o" + style, color="tab:blue", label=rf"$\varepsilon_{{LOO}}^{{mean}}$ ({label})")
            ax.semilogy(n_s, h["empirical"].sel(variable=v).values, "s" + style, color="tab:orange",
                        label=rf"$\varepsilon_{{emp}}^{{mean}}$ ({label})")
            for n, e, p in zip(n_s, loo, h["degree"].values):
                if np.isfinite(p):
                    ax.annotate(f"p={p:.0f}", (n, e), textcoords="offset points", xytext=(3, 4), fontsize=7)
        ax.set_title(v if v.startswith("all") else f"{v} profile")
        ax.set_xlabel("training runs N_s")
        ax.grid(alpha=0.3, which="both")
        ax.legend(fontsize=8)
    axes[0, 0].set_ylabel("mean relative error over the outputs (1)")
    fig.suptitle("Proxy errors on the training design vs its size (cf. thesis Fig. 3.3)", fontsize=11)
    return _save(fig, path)


def proxy_vs_simulator_figure(surrogate: xr.Dataset | Mapping[str, xr.Dataset], design: xr.Dataset,
                              responses: xr.Dataset, path: str | Path, *, variables: Sequence[str] = ("dp", "recovery"),
                              experiment: str = "BCF1") -> Path:
    """Figs. 3.4-3.5: proxy mean vs simulator at the points of a validation ``design`` (``responses``: the
    ``forward`` stage's runs there); one row per variable, one column per surrogate. Grey: every (point, PV step),
    with its R² and relative L2 error (Eq. 3.15); blue: the thesis's scalar QoI (max Δp over PV, the final value of
    other variables) with its R² (the same numbers as ``surrogate_validation``'s ``r2_max``/``r2_final``)."""
    data = {label: scatter_data(ds, design, responses, variables=variables, experiment=experiment)
            for label, ds in _labelled(surrogate).items()}
    fig, axes = subplots(len(variables), len(data), figsize=(4.3 * len(data), 4 * len(variables)), squeeze=False)
    for j, (label, d) in enumerate(data.items()):
        for i, v in enumerate(variables):
            ax, stats = axes[i, j], d.sel(variable=v)
            scale, name = _axis(v, d[f"{v}_simulator"].attrs["units"])
            sim = d[f"{v}_simulator"].dropna("pv", how="all").values * scale
            proxy = d[f"{v}_proxy"].dropna("pv", how="all").values * scale
            ax.plot(sim.ravel(), proxy.ravel(), ".", ms=2, alpha=0.25, color="0.5",
                    label=f"every PV step: R² = {float(stats['r2_pooled']):.4f}, "
                          f"L2 = {float(stats['l2_pooled']):.1e}")
            if _SCALAR.get(v) == "max":
                qoi, s, p, r2 = "max over PV", sim.max(axis=1), proxy.max(axis=1), stats["r2_max"]
            else:
                qoi, s, p, r2 = "final value", sim[:, -1], proxy[:, -1], stats["r2_final"]
            ax.plot(s, p, ".", ms=4, alpha=0.7, color="tab:blue", label=f"{qoi}: R² = {float(r2):.4f}")
            lims = [min(sim.min(), proxy.min()), max(sim.max(), proxy.max())]
            ax.plot(lims, lims, "k-", lw=0.8)
            ax.set_xlabel(f"simulator {name}")
            ax.set_ylabel(f"proxy {name}")
            ax.set_title(label, fontsize=10)
            ax.legend(fontsize=7, loc="upper left")
    n = next(iter(data.values())).attrs["n_validation"]
    fig.suptitle(f"Proxy vs simulator on {n} independent runs of {experiment} (cf. thesis Figs. 3.4-3.5)")
    return _save(fig, path)


def moments_figure(surrogate: xr.Dataset | Mapping[str, xr.Dataset], responses: xr.Dataset, path: str | Path, *,
                   design: xr.Dataset | None = None, variables: Sequence[str] = ("dp", "recovery"),
                   experiment: str = "BCF1") -> Path:
    """Figs. 3.8-3.9: mean (left) and standard deviation (right) over PV of each surrogate (lines; PCE: Eqs.
    3.11-3.12 from the coefficients, other kinds: moments of the predictions at ``design``, which is then required)
    against the sample moments of the runs ``responses`` (dots); the legend gives the relative L2 errors of the
    mean and variance curves (Eq. 3.15, as in Fig. 3.7)."""
    data = {label: moment_data(ds, responses, design=design, variables=variables, experiment=experiment)
            for label, ds in _labelled(surrogate).items()}
    fig, axes = subplots(len(variables), 2, figsize=(10.5, 3.5 * len(variables)), sharex=True, squeeze=False)
    for k, (label, d) in enumerate(data.items()):
        for i, v in enumerate(variables):
            scale, name = _axis(v, d[f"{v}_proxy_mean"].attrs["units"])
            stats = d.sel(variable=v)
            for ax, what, err in ((axes[i, 0], "mean", "mean_l2_error"), (axes[i, 1], "std", "variance_l2_error")):
                curve = d[f"{v}_proxy_{what}"].dropna("pv")
                ax.plot(curve["pv"], curve * scale, color=f"C{k}",
                        label=f"{label}: L2 {'mean' if what == 'mean' else 'variance'} = {float(stats[err]):.1e}")
                if k == len(data) - 1:
                    sample = d[f"{v}_sample_{what}"].dropna("pv")
                    ax.plot(sample["pv"], sample * scale, "k.", ms=4, label=f"{d.attrs['n_runs']} runs")
                    ax.set_ylabel(f"{what} of {name}")
                    ax.legend(fontsize=7)
    for ax in axes[-1]:
        ax.set_xlabel("injected pore volumes (PV)")
    moments = "; ".join(sorted({d.attrs["moments"] for d in data.values()}))
    fig.suptitle(f"Proxy moments vs runs of {experiment} (cf. thesis Figs. 3.8-3.9)\nproxy moments: {moments}",
                 fontsize=10)
    return _save(fig, path)


def band_figure(surrogate: xr.Dataset, design: xr.Dataset, responses: xr.Dataset, path: str | Path, *,
                n_show: int = 3, reference: xr.Dataset | None = None, variables: Sequence[str] = ("dp", "recovery"),
                experiment: str = "BCF1", schedule=None) -> Path:
    """Fig. 3.15: for the first ``n_show`` validation points, the surrogate's mean ± 2σ over PV (σ² its predicted
    variance), the simulator (markers) and optionally a ``reference`` surrogate's mean (dashed, e.g. the PCE);
    below, the same band around the mean with the simulator's offset from it. Dotted lines: slug ends of
    ``schedule`` (anything :func:`~spflow.plugins.forward.schedule.as_schedule` takes; default: ``experiment``'s
    Table 2.5 schedule). Titles give the fraction of all validation values inside the band."""
    d = band_data(surrogate, design, responses, n_show=n_show, reference=reference, variables=variables,
                  experiment=experiment)
    fig, axes = subplots(2, len(variables), figsize=(5.5 * len(variables), 7.5), sharex=True, squeeze=False,
                             gridspec_kw={"height_ratios": [3, 2]})
    slug_ends = np.cumsum([slug.pv for slug in as_schedule(experiment if schedule is None else schedule).slugs])[:-1]
    name_of = surrogate_label(surrogate)
    for (ax, ax_err), v in zip(axes.T, variables):
        scale, name = _axis(v, d[f"{v}_mean"].attrs["units"])
        shown = ("mean", "std", "simulator") + (("reference_mean",) if reference is not None else ())
        curves = d[[f"{v}_{s}" for s in shown]].dropna("pv", how="all")
        pv = curves["pv"].values
        ends = slug_ends[slug_ends < pv.max()]
        for k in range(curves.sizes["sample"]):
            c, first = curves.isel(sample=k), k == 0
            mean, sd, sim = (c[f"{v}_{s}"].values * scale for s in ("mean", "std", "simulator"))
            colour = f"C{k}"
            ax.fill_between(pv, mean - 2 * sd, mean + 2 * sd, color=colour, alpha=0.3, lw=0,
                            label=f"{name_of} ±2σ" if first else None)
            ax.plot(pv, mean, color=colour, lw=1.4, label=f"{name_of} mean" if first else None)
            if reference is not None:
                ref = c[f"{v}_reference_mean"].values * scale
                ax.plot(pv, ref, color=colour, lw=1.0, ls="--",
                        label=f"{surrogate_label(reference)} mean" if first else None)
                ax_err.plot(pv, sim - ref, color=colour, lw=0.8, ls="--")
            ax.plot(pv, sim, "o", ms=3, mfc="none", color=colour, label="simulator" if first else None)
            ax_err.fill_between(pv, -2 * sd, 2 * sd, color=colour, alpha=0.25, lw=0)
            ax_err.plot(pv, sim - mean, "o-", ms=2.5, lw=0.8, mfc="none", color=colour)
        for boundary in ends:
            ax.axvline(boundary, color="0.6", lw=0.8, ls=":")
            ax_err.axvline(boundary, color="0.6", lw=0.8, ls=":")
        ax.set_ylabel(name)
        ax.set_title(f"{experiment} {v}: {curves.sizes['sample']} validation points; "
                     f"{100 * float(d['coverage'].sel(variable=v)):.0f} % of {d.attrs['n_validation']} runs × PV "
                     f"inside ±2σ", fontsize=9)
        ax_err.axhline(0.0, color="k", lw=0.6)
        ax_err.set_ylabel(f"simulator − proxy mean ({name.split('(')[-1].rstrip(')')})")
        ax_err.set_xlabel("injected pore volumes (PV)")
        ax_err.set_title("±2σ band (shaded), simulator − mean (o)" + (", − reference (--)" if reference is not None
                                                                       else ""), fontsize=9)
    axes[0, 0].legend(loc="best", fontsize=8)
    fig.suptitle(f"{name_of}: mean ± 2σ vs simulator (cf. thesis Fig. 3.15)")
    return _save(fig, path)
