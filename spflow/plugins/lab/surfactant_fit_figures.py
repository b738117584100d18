"""Goodness-of-fit figures of the surfactant lab fits: thesis Figs. 2.5 (phase behaviour), 2.6 (IFT), 2.7 (ME
viscosity) and 2.8 (capillary desaturation). Each takes the FIT dataset of its stage and a PNG path."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib import colormaps
from matplotlib.figure import Figure

from spflow.plugins.lab.fit_result import fit_interval

__all__ = ["phase_behaviour_figure", "ift_figure", "me_viscosity_figure", "desaturation_figure"]


def _estimates_text(fit, level: float = 0.95) -> str:
    lo, hi = fit_interval(fit, level)
    lines = [f"{name} = {float(est):.4g}  [{float(a):.4g}, {float(b):.4g}]"
             for name, est, a, b in zip(fit["param"].values, fit["estimate"].values, lo.values, hi.values)]
    return f"estimate [{round(100 * level)} % interval]\n" + "\n".join(lines)


def _figure():
    """A figure with one axes and room on the right for the estimates box."""
    fig = Figure(figsize=(9.5, 4.6))
    ax = fig.add_axes((0.08, 0.12, 0.6, 0.78))
    return fig, ax


def _finish(fig, ax, fit, path) -> Path:
    """Estimates box right of the axes, grid, save as PNG."""
    fig.text(0.70, 0.12, _estimates_text(fit), fontsize=7.5, va="bottom", ha="left", family="monospace",
             bbox={"facecolor": "white", "edgecolor": "0.7"})
    ax.grid(True, which="both", alpha=0.25)
    path = Path(path)
    fig.savefig(path, dpi=130)
    return path


def phase_behaviour_figure(fit, path) -> Path:
    """Fig. 2.5(b): solubilization ratios V_w/V_s and V_o/V_s vs salinity, readings and Hand's-rule fit, with the
    fitted type III window [CSEL, CSEU] shaded."""
    fig, ax = _figure()
    csel, cseu = (float(fit["estimate"].sel(param=n)) for n in ("CSEL", "CSEU"))
    ax.axvspan(csel, cseu, color="0.88", label="type III (fitted CSEL-CSEU)")
    s = fit["curve_salinity"].values
    ax.plot(s, fit["curve_r_water"], color="tab:blue", label="Hand's rule fit, V_w/V_s")
    ax.plot(s, fit["curve_r_oil"], color="tab:red", label="Hand's rule fit, V_o/V_s")
    ax.plot(fit["salinity"], fit["r_water"], "o", mfc="none", color="tab:blue", label="pipette reading V_w/V_s")
    ax.plot(fit["salinity"], fit["r_oil"], "s", mfc="none", color="tab:red", label="pipette reading V_o/V_s")
    ax.set_yscale("log")
    ax.set_xlabel("effective salinity C_SE (meq/ml)")
    ax.set_ylabel("solubilization ratio (-)")
    ax.set_title(f"Fig. 2.5: phase behaviour, {fit.attrs.get('experiment', '')}", fontsize=9)
    ax.legend(fontsize=7.5, loc="upper left", bbox_to_anchor=(1.02, 1.0))
    return _finish(fig, ax, fit, path)


def ift_figure(fit, path) -> Path:
    """Fig. 2.6: IFT vs solubilization ratio, measured water/ME and oil/ME tensions and the fitted Chun-Huh law
    (Eq. 2.9 with F = 1; points with F < 1 lie below it)."""
    fig, ax = _figure()
    ax.plot(fit["curve_ratio"], fit["curve_ift"], color="k", label="Chun-Huh fit (F = 1)")
    interface = fit["interface"].values
    for code, marker, color, label in ((1, "o", "tab:blue", "water/ME, vs R13"), (2, "s", "tab:red", "oil/ME, vs R23")):
        sel = interface == code
        ax.plot(fit["ratio"].values[sel], fit["ift"].values[sel], marker, mfc="none", color=color, label=label)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("solubilization ratio R_l3 (-)")
    ax.set_ylabel("IFT (mN/m)")
    ax.set_title(f"Fig. 2.6: IFT, sigma_ow = {fit.attrs['sigma_ow']:.3g} mN/m, {fit.attrs.get('experiment', '')}",
                 fontsize=9)
    ax.legend(fontsize=7.5, loc="upper left", bbox_to_anchor=(1.02, 1.0))
    return _finish(fig, ax, fit, path)


def me_viscosity_figure(fit, path) -> Path:
    """Fig. 2.7: ME viscosity vs oil solubilization ratio C2/C3, one colour per surfactant fraction, data and
    the fitted Eq. 2.11."""
    fig, ax = _figure()
    levels = fit["curve_surfactant"].values
    colors = colormaps["viridis"](np.linspace(0.0, 0.85, levels.size))
    surf = fit["surfactant"].values
    for level, color in zip(levels, colors):
        ax.plot(fit["curve_ratio"], fit["curve_viscosity"].sel(curve_surfactant=level), color=color,
                label=f"C3 = {level:g}")
        sel = np.isclose(surf, level)
        ax.plot(fit["r_oil"].values[sel], fit["viscosity"].values[sel], "o", mfc="none", color=color)
    ax.set_xscale("log")
    ax.set_xlabel("oil solubilization ratio C23/C33 (-)")
    ax.set_ylabel("microemulsion viscosity (cP)")
    ax.set_title(f"Fig. 2.7: ME viscosity (lines: Eq. 2.11 fit, circles: data; held {fit.attrs['fixed']})",
                 fontsize=8)
    ax.legend(fontsize=7.5, loc="upper left", bbox_to_anchor=(1.02, 1.0), title="surfactant fraction",
              title_fontsize=7.5)
    ax.set_ylim(bottom=0.0)
    return _finish(fig, ax, fit, path)


def desaturation_figure(fit, path) -> Path:
    """Fig. 2.8: residual saturation vs capillary number, data and the fitted Eq. 2.12 with its plateaus."""
    fig, ax = _figure()
    names = [str(n) for n in fit["param"].values]
    t_l, s_low, s_high = (float(fit["estimate"].sel(param=n)) for n in names)
    ax.plot(fit["curve_capillary_number"], fit["curve_saturation"], color="k", label="Eq. 2.12 fit (tau = 1)")
    ax.plot(fit["capillary_number"], fit["residual_saturation"], "o", mfc="none", color="tab:red", label="measured")
    ax.axhline(s_low, color="0.5", ls=":", lw=1)
    ax.axhline(s_high, color="0.5", ls=":", lw=1)
    ax.axvline(1.0 / t_l, color="tab:blue", ls="--", lw=1, label=f"N = 1/{names[0]} (half-way)")
    ax.set_xscale("log")
    ax.set_xlabel("capillary number N_c (-)")
    ax.set_ylabel(f"residual saturation of phase {fit.attrs['phase']} (-)")
    ax.set_title(f"Fig. 2.8: capillary desaturation, {fit.attrs.get('experiment', '')}", fontsize=9)
    ax.legend(fontsize=7.5, loc="upper left", bbox_to_anchor=(1.02, 1.0))
    return _finish(fig, ax, fit, path)
