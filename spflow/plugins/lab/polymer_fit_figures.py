"""Goodness-of-fit figures of lab fits A: Figs. 2.2, 2.3, 2.4, 2.9 and the adsorption isotherm (thesis chapter 2).

Each function takes the FIT dataset of its stage (:mod:`.polymer_fit_stages`) and a path, draws the lab data with the
fitted model (curves recomputed from the estimates with the same model functions the fit used) and returns the path.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import xarray as xr

from spflow.core.figure import subplots
from spflow.plugins.forward.physics.shear_thinning import half_shear_rate

from .adsorption_fit import isotherm
from .polymer_rheology import NAMES as RHEOLOGY_NAMES
from .polymer_rheology import rheology_viscosity
from .tracer_fit import effluent_conductivity

__all__ = ["polymer_rheology_figure", "half_shear_rate_figure", "polymer_coreflood_figure", "adsorption_figure",
           "tracer_figure"]


def _estimates(fit: xr.Dataset) -> dict[str, float]:
    return {str(p): float(v) for p, v in zip(fit["param"].values, fit["estimate"].values)}


def _save(fig, path) -> Path:
    path = Path(path)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    return path


def _pm(value: float, std: float) -> str:
    """``value +/- std`` rounded to the second significant digit of ``std``."""
    digits = max(0, 1 - int(np.floor(np.log10(std)))) if std > 0 else 3
    return f"{value:.{digits}f} +/- {std:.{digits}f}"


def _brines(fit):
    keys = np.column_stack([fit["sweep_anions"].values, fit["sweep_divalent"].values])
    return np.unique(keys, axis=0)


def _brine_label(c51, c61):
    return f"C51 {c51:.3f}, C61 {c61:.4f} meq/ml"


def polymer_rheology_figure(fit: xr.Dataset, path) -> Path:
    """Fig. 2.2: zero-shear viscosity vs concentration per brine (a), vs C_SEP per concentration (b, Eq. 2.2),
    and viscosity vs shear rate at the first brine (c). Points: per-sweep Meter fits / readings; lines: joint fit."""
    est = {n: _estimates(fit)[n] for n in RHEOLOGY_NAMES}
    mu_w, cse1 = fit.attrs["water_viscosity_cp"], fit.attrs["cse1_meq_ml"]
    fig, axes = subplots(1, 3, figsize=(15, 4.6))
    cp_line = np.linspace(0.0, fit["sweep_c_polymer"].values.max() * 1.1, 100)
    for k, (c51, c61) in enumerate(_brines(fit)):
        sel = (fit["sweep_anions"].values == c51) & (fit["sweep_divalent"].values == c61)
        color = f"C{k}"
        axes[0].errorbar(fit["sweep_c_polymer"].values[sel], fit["sweep_mu0"].values[sel],
                         yerr=2 * fit["sweep_mu0_std"].values[sel], fmt="o", color=color, label=_brine_label(c51, c61))
        axes[0].plot(cp_line, rheology_viscosity(est, cp_line, c51, c61, 0.0, mu_w, cse1), color=color)
    axes[0].set(xlabel="polymer concentration (wt %)", ylabel="zero-shear viscosity (cP)",
                title="(a) Eq. 2.1 at several brines")
    axes[0].legend(fontsize=7)
    csep_line = np.geomspace(fit["sweep_csep"].values.min() * 0.8, fit["sweep_csep"].values.max() * 1.2, 100)
    for k, cp in enumerate(np.unique(fit["sweep_c_polymer"].values)):
        sel = fit["sweep_c_polymer"].values == cp
        axes[1].plot(fit["sweep_csep"].values[sel], (fit["sweep_mu0"].values[sel] - mu_w) / mu_w, "o", color=f"C{k}",
                     label=f"{cp:g} wt %")
        # C61 = 0 makes C_SEP = C51 whatever BETAP
        axes[1].plot(csep_line, (rheology_viscosity(est, cp, csep_line, 0.0, 0.0, mu_w, cse1) - mu_w) / mu_w,
                     color=f"C{k}")
    axes[1].set(xscale="log", yscale="log", xlabel="effective salinity C_SEP (meq/ml)",
                ylabel="(mu_p0 - mu_w) / mu_w", title=f"(b) Eq. 2.2, SSLOPE = {est['SSLOPE']:.3f}")
    axes[1].legend(fontsize=7)
    c51, c61 = _brines(fit)[0]
    pts = (fit["anions"].values == c51) & (fit["divalent"].values == c61)
    g_line = np.geomspace(fit["shear_rate"].values.min(), fit["shear_rate"].values.max(), 100)
    for k, cp in enumerate(np.unique(fit["c_polymer"].values[pts])):
        sel = pts & (fit["c_polymer"].values == cp)
        axes[2].plot(fit["shear_rate"].values[sel], fit["viscosity"].values[sel], "o", color=f"C{k}",
                     label=f"{cp:g} wt %")
        axes[2].plot(g_line, rheology_viscosity(est, cp, c51, c61, g_line, mu_w, cse1), color=f"C{k}")
    axes[2].set(xscale="log", yscale="log", xlabel="shear rate (1/s)", ylabel="viscosity (cP)",
                title=f"(c) Eq. 2.4, POWN = {est['POWN']:.3f}")
    axes[2].legend(fontsize=7, title=_brine_label(c51, c61), title_fontsize=7)
    return _save(fig, path)


def half_shear_rate_figure(fit: xr.Dataset, path) -> Path:
    """Fig. 2.3: per-sweep half shear rates vs concentration per brine, with the Eq. 2.5 fit."""
    est = _estimates(fit)
    cse1 = fit.attrs["cse1_meq_ml"]
    fig, ax = subplots(figsize=(6.5, 4.6))
    cp_line = np.linspace(fit["sweep_c_polymer"].values.min() * 0.8, fit["sweep_c_polymer"].values.max() * 1.1, 100)
    for k, (c51, c61) in enumerate(_brines(fit)):
        sel = (fit["sweep_anions"].values == c51) & (fit["sweep_divalent"].values == c61)
        csep = max(c51 + (est["BETAP"] - 1.0) * c61, cse1)
        ax.errorbar(fit["sweep_c_polymer"].values[sel], fit["sweep_gamma_half"].values[sel],
                    yerr=2 * fit["sweep_gamma_half_std"].values[sel], fmt="o", color=f"C{k}",
                    label=f"C_SEP {csep:.3f} meq/ml")
        ax.plot(cp_line, [half_shear_rate(csep, c, est["A0"], est["A1"], est["A2"]) for c in cp_line], color=f"C{k}")
    ax.set(yscale="log", xlabel="polymer concentration (wt %)", ylabel="half shear rate (1/s)",
           title=f"Eq. 2.5: a0 = {est['A0']:.0f}, a1 = {est['A1']:.0f}, a2 = {est['A2']:.2f}")
    ax.legend(fontsize=8)
    return _save(fig, path)


def polymer_coreflood_figure(fit: xr.Dataset, path) -> Path:
    """Fig. 2.4: pressure history of the single-phase polymer coreflood, data and fitted simulator."""
    est = _estimates(fit)
    fig, ax = subplots(figsize=(8, 4.6))
    pv, to_kpa = fit["pv"].values, 1e-3
    ax.plot(pv, fit["dp"].values * to_kpa, "o", ms=3, color="k", label="lab data")
    ax.plot(pv, fit["dp_fit"].values * to_kpa, color="C3",
            label=f"fit: PERM {est['PERM']:.0f} mD, BRK {est['BRK']:.1f}, CRK {est['CRK']:.4f}")
    ax2 = ax.twinx()
    ax2.step(pv, fit["c_polymer_in"].values, where="pre", color="C0", alpha=0.5)
    ax2.set_ylabel("injected polymer (ppm)", color="C0")
    ax.set(xlabel="injected pore volumes", ylabel="pressure drop (kPa)", yscale="log",
           title="Single-phase polymer coreflood (Eqs. 2.6-2.8)")
    ax.legend(loc="upper left", fontsize=8)
    return _save(fig, path)


def adsorption_figure(fit: xr.Dataset, path) -> Path:
    """Langmuir isotherm (Eqs. 2.15-2.16): retention data and fit per brine, in mg/g of rock."""
    names = [str(p) for p in fit["param"].values]
    a1, a2, b = fit["estimate"].values
    label = ", ".join(f"{n} {_pm(v, s)}" for n, v, s in zip(names, fit["estimate"].values, fit["std"].values))
    factor = fit.attrs["pv_factor"]
    conc, sal = fit["concentration"].values, fit["salinity"].values
    unit = fit["concentration"].attrs.get("units", "")
    fig, ax = subplots(figsize=(6.5, 4.6))
    c_line = np.linspace(0.0, conc.max() * 1.05, 200)
    for k, tds in enumerate(np.unique(sal)):
        sel = sal == tds
        cse = float(fit["cse"].values[sel][0])
        ax.plot(conc[sel], fit["adsorbed"].values[sel], "o", color=f"C{k}", label=f"{tds:g} ppm TDS")
        ax.plot(c_line, isotherm(c_line, cse, a1, a2, b) / factor, color=f"C{k}")
    ax.set(xlabel=f"equilibrium concentration ({unit})", ylabel="retention (mg/g rock)")
    ax.set_title(f"{fit.attrs['component']} Langmuir isotherm (Eqs. 2.15-2.16)\n{label}", fontsize=9)
    ax.legend(fontsize=8)
    return _save(fig, path)


def tracer_figure(fit: xr.Dataset, path) -> Path:
    """Fig. 2.9: (a) linear TDS-EC calibration, (b) effluent conductivity vs PV with the Ogata-Banks fit."""
    alpha, slope = fit["estimate"].values
    fig, axes = subplots(1, 2, figsize=(12, 4.6))
    tds = fit["calibration_tds"].values
    t_line = np.linspace(0.0, tds.max() * 1.1, 50)
    axes[0].plot(fit["calibration_conductivity"].values, tds, "o", label="calibration brines")
    axes[0].plot(t_line / slope, t_line, label=f"TDS = {slope:.1f} x EC")
    axes[0].set(xlabel="conductivity (mS/cm)", ylabel="TDS (ppm)", title="(a) TDS-EC relation")
    axes[0].legend()
    pv = fit["pv"].values
    pv_line = np.linspace(0.0, pv.max(), 300)
    ec_line = effluent_conductivity(pv_line, alpha, slope, fit.attrs["length_m"], fit.attrs["initial_tds_ppm"],
                                    fit.attrs["injected_tds_ppm"])
    axes[1].plot(pv, fit["conductivity"].values, "o", ms=3, color="k", label="effluent")
    axes[1].plot(pv_line, ec_line, color="C3", label=f"Ogata-Banks, ALPHAL = {alpha:.4f} ft (Pe {fit.attrs['peclet']:.0f})")
    axes[1].set(xlabel="injected pore volumes", ylabel="conductivity (mS/cm)", title="(b) effluent conductivity")
    axes[1].legend()
    return _save(fig, path)
