"""Figures of a Bayesian calibration (matplotlib, Agg): the thesis's appendices B-E and Figs. 4.4-4.5.

* :func:`trace_figure` — traces of every parameter (App. B), one line per independent chain (for emcee: the first
  walker of each run);
* :func:`autocorrelation_figure` — autocorrelation of the kept draws against lag (App. C, Eq. C.1);
* :func:`prior_posterior_figure` — posterior histogram over the prior density (App. D; uniform on the box, or the
  marginal the posterior records for the parameter), optional truth;
* :func:`geweke_figure` — Geweke z of sub-chains starting further and further in (App. E), ±2 bands, one colour per
  independent chain (for emcee: each run's walker mean);
* :func:`predictive_figure` — posterior predictive bands with the observations (Fig. 4.4 for the training coreflood,
  Fig. 4.5 for the held-out ones), optionally over the prior band.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import xarray as xr

from spflow.core.figure import subplots

from .diagnostics import autocorrelation, geweke_intervals, independent_series
from .parameter_prior import ParameterPrior

__all__ = ["trace_figure", "autocorrelation_figure", "prior_posterior_figure", "geweke_figure", "predictive_figure"]

_QOI_LABELS = {"dp": ("Δp (kPa)", 1e-3), "oil_cut": ("oil cut (–)", 1.0), "recovery": ("recovery (–)", 1.0)}


def _grid(n: int, width: float = 3.2, height: float = 2.4):
    cols = min(3, n)
    rows = -(-n // cols)
    fig, axes = subplots(rows, cols, figsize=(width * cols, height * rows), squeeze=False)
    for ax in axes.flat[n:]:
        ax.set_visible(False)
    return fig, axes.flat


def _independent(posterior: xr.Dataset) -> xr.Dataset:
    """One chain per independent run (emcee: walker 0 of each run; MH: every chain)."""
    if "chain_walker" in posterior.coords:
        return posterior.isel(chain=np.flatnonzero(posterior["chain_walker"].values == 0))
    return posterior


def _label(posterior: xr.Dataset, name: str) -> str:
    unit = str(posterior["unit"].sel(param=name).values) if "unit" in posterior else ""
    return f"{name} [{unit}]" if unit and unit != "-" else name


def _save(fig, path: Path, title: str) -> Path:
    fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    return path


def trace_figure(posterior: xr.Dataset, path: Path) -> Path:
    sub = _independent(posterior)
    names = [str(n) for n in posterior["param"].values]
    fig, axes = _grid(len(names))
    step = int(posterior.attrs.get("thin", 1))
    for ax, name in zip(axes, names):
        for c in range(sub.sizes["chain"]):
            series = sub["theta"].isel(chain=c).sel(param=name).values
            ax.plot(np.arange(series.size) * step, series, lw=0.4, alpha=0.8)
        ax.set_ylim(float(posterior["lower"].sel(param=name)), float(posterior["upper"].sel(param=name)))
        ax.set_title(_label(posterior, name), fontsize=9)
        ax.set_xlabel("step after burn-in", fontsize=8)
    return _save(fig, path, f"Traces ({posterior.attrs.get('sampler', '')}, one line per independent chain)")


def autocorrelation_figure(posterior: xr.Dataset, path: Path, max_lag: int = 60) -> Path:
    names = [str(n) for n in posterior["param"].values]
    fig, axes = _grid(len(names))
    theta = posterior["theta"].transpose("chain", "draw", "param").values
    lag = min(max_lag, theta.shape[1] - 1)
    for ax, (k, name) in zip(axes, enumerate(names)):
        ax.bar(np.arange(lag + 1), autocorrelation(theta[:, :, k], lag), width=0.8)
        ax.axhline(0.0, color="k", lw=0.5)
        ax.set_ylim(-0.2, 1.0)
        ax.set_title(_label(posterior, name), fontsize=9)
        ax.set_xlabel(f"lag (kept draws, thin {posterior.attrs.get('thin', 1)})", fontsize=8)
    return _save(fig, path, "Autocorrelation of the kept draws (averaged over chains)")


def prior_posterior_figure(posterior: xr.Dataset, path: Path, truth: dict[str, float] | None = None) -> Path:
    names = [str(n) for n in posterior["param"].values]
    prior = ParameterPrior.of_posterior(posterior, "prior_posterior_figure: the posterior")
    fig, axes = _grid(len(names))
    for ax, name, law in zip(axes, names, prior.inputs):
        lo, hi = float(posterior["lower"].sel(param=name)), float(posterior["upper"].sel(param=name))
        ax.hist(posterior["theta"].sel(param=name).values.ravel(), bins=50, range=(lo, hi), density=True,
                alpha=0.6, label="posterior")
        grid = np.linspace(lo, hi, 201)
        ax.plot(grid, np.exp(law.logpdf(grid)), color="k", ls="--", label="prior")
        if truth and name in truth:
            ax.axvline(truth[name], color="r", lw=1.2, label="truth")
        ax.set_xlim(lo, hi)
        ax.set_title(_label(posterior, name), fontsize=9)
        ax.set_yticks([])
    axes[0].legend(fontsize=7)
    title = "uniform on the box" if prior.uniform else "marginals of the space"
    return _save(fig, path, f"Prior ({title}) and posterior")


def geweke_figure(posterior: xr.Dataset, path: Path) -> Path:
    series = independent_series(posterior)
    names = [str(n) for n in posterior["param"].values]
    fig, axes = _grid(len(names))
    step = int(posterior.attrs.get("thin", 1))
    for ax, (k, name) in zip(axes, enumerate(names)):
        for chain in series[:, :, k]:
            starts, z = geweke_intervals(chain)
            ax.plot(starts * step, z, "o", ms=2.5)
        ax.axhspan(-2, 2, color="0.9", zorder=0)
        ax.set_ylim(-4, 4)
        ax.set_title(_label(posterior, name), fontsize=9)
        ax.set_xlabel("first step of the sub-chain", fontsize=8)
    return _save(fig, path, "Geweke z (spectral variance) of sub-chains; shaded |z| < 2")


def predictive_figure(bands: xr.Dataset, observations: xr.Dataset | None, experiments: list[str], path: Path,
                      variables: tuple[str, ...] = ("dp", "oil_cut"), prior: xr.Dataset | None = None,
                      title: str = "") -> Path:
    """Bands between the outer quantile levels of ``bands`` (``posterior_predictive`` output) per QoI (rows) and
    experiment (columns); ``prior``, a ``quantiles`` output over prior draws, adds the prior band."""
    lo_q, hi_q = float(bands.attrs["band_low"]), float(bands.attrs["band_high"])
    mid_q = sorted(float(q) for q in bands["quantile"].values)[len(bands["quantile"]) // 2]
    pct = round(100 * (hi_q - lo_q))
    fig, axes = subplots(len(variables), len(experiments), squeeze=False, sharex="col",
                         figsize=(max(4.2 * len(experiments), 7.0), 3.0 * len(variables)))
    for j, exp in enumerate(experiments):
        end = float(bands["total_pv"].sel(experiment=exp)) if "total_pv" in bands else np.inf
        for i, var in enumerate(variables):
            ax = axes[i, j]
            label, scale = _QOI_LABELS.get(var, (var, 1.0))
            sel = bands.sel(experiment=exp).sel(pv=slice(0, end)).dropna("pv", subset=[var])  # other runs' grid points
            pv = sel["pv"].values
            if prior is not None and var in prior:
                pri = prior.sel(experiment=exp).sel(pv=slice(0, end)).dropna("pv", subset=[var])
                ax.fill_between(pri["pv"], pri[var].sel(quantile=lo_q, method="nearest") * scale,
                                pri[var].sel(quantile=hi_q, method="nearest") * scale, color="0.85",
                                label=f"prior {pct}% band")
            if f"{var}_predictive" in sel:
                ax.fill_between(pv, sel[f"{var}_predictive"].sel(quantile=lo_q) * scale,
                                sel[f"{var}_predictive"].sel(quantile=hi_q) * scale, color="tab:blue", alpha=0.25,
                                label=f"predictive {pct}% (with noise)")
            ax.fill_between(pv, sel[var].sel(quantile=lo_q) * scale, sel[var].sel(quantile=hi_q) * scale,
                            color="tab:blue", alpha=0.55, label=f"model {pct}% (parameters)")
            ax.plot(pv, sel[var].sel(quantile=mid_q) * scale, color="navy", lw=1.2, label="posterior median")
            if observations is not None and var in observations and exp in observations["experiment"].values:
                obs = observations[var].sel(experiment=exp).dropna("pv")
                ax.plot(obs["pv"], obs * scale, ".", color="k", ms=3, label="observed")
            cover = bands.get(f"coverage_{var}")
            title_bits = [exp]
            if cover is not None and np.isfinite(float(cover.sel(experiment=exp))):
                title_bits.append(f"coverage {100 * float(cover.sel(experiment=exp)):.0f}%")
            ax.set_title(", ".join(title_bits), fontsize=9)
            ax.set_ylabel(label)
            if i == len(variables) - 1:
                ax.set_xlabel("injected pore volumes (PV)")
    axes[0, 0].legend(fontsize=7, loc="best")
    return _save(fig, path, title or "Posterior predictive")
