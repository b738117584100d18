"""Fig. 3.2-style figure: total Sobol' index S_i^T (Eq. 3.3) of every parameter, one panel per sub-model, bars for
final oil recovery and maximum pressure drop, with the bootstrap interval and the selected parameters marked."""

from __future__ import annotations

import numpy as np
import xarray as xr
from matplotlib import rcParams

from spflow.core.figure import subplots

__all__ = ["THESIS_SYMBOLS", "plot_total_indices"]

#: Thesis notation (Table 3.1, Fig. 3.2) of the UTCHEM names.
THESIS_SYMBOLS = {
    **{f"ALPHAV{i}": rf"$\alpha_{{V{i}}}$" for i in range(1, 6)},
    "HBNC70": r"$C_0$", "HBNC71": r"$C_1$", "HBNC72": r"$C_2$",
    "AD31": r"$ad_{31}$", "AD32": r"$ad_{32}$", "B3D": r"$b_{3d}$",
    "GAMHF": r"$\dot\gamma_{1/2}$", "CRK": r"$c_{rk}$", "BRK": r"$b_{rk}$",
    "E2C": r"$n_{high}$", "E2WC": r"$n_{low}$",
    **{f"ALPHAL{i}": rf"$\alpha_{{L{i}}}$" for i in range(1, 4)},
}

_QOI_LABELS = {"recovery_final": "final recovery", "dp_max": r"max $\Delta p$"}


def _spread(sel: xr.Dataset) -> str:
    sd = float(np.sqrt(sel["variance"].max()))
    unit = str(sel["qoi_units"].values)
    return f"{sd:.2g}" if unit == "1" else f"{sd:.3g} {unit}"


def plot_total_indices(screening: xr.Dataset, qois: list[str] | None = None, *, index: str = "ST", ncols: int = 4,
                       title: str | None = None):
    """Bar charts of ``index`` (default S_i^T) per parameter, one panel per ``group``, one bar per QoI label.

    ``qois`` are labels of the ``qoi`` coordinate (default: every ``recovery_final``/``dp_max`` QoI). Error bars are
    the ``<index>_conf`` half-widths; selected parameters get a star and a bold label. Each panel's title gives the
    standard deviation of every QoI over the design the group was screened in: in ``per_group`` mode the indices are
    shares of that group's own variance, so this is what makes panels comparable. Returns the Figure.
    """
    if qois is None:
        qois = [str(q) for q, v in zip(screening["qoi"].values, screening["qoi_variable"].values) if v in _QOI_LABELS]
    groups = list(dict.fromkeys(screening["group"].values.tolist()))
    nrows = -(-len(groups) // ncols)
    fig, axes = subplots(nrows, ncols, figsize=(3.3 * ncols, 2.9 * nrows), squeeze=False)
    width = 0.8 / len(qois)
    colours = rcParams["axes.prop_cycle"].by_key()["color"]
    for ax, group in zip(axes.flat, groups):
        sub = screening.isel(param=np.flatnonzero(screening["group"].values == group))
        x = np.arange(sub.sizes["param"])
        for k, qoi in enumerate(qois):
            sel = sub.sel(qoi=qoi)
            variable, experiment = str(sel["qoi_variable"].values), str(sel["qoi_experiment"].values)
            label = f"{_QOI_LABELS.get(variable, variable)} ({experiment})" if experiment else variable
            ax.bar(x + (k - (len(qois) - 1) / 2) * width, sel[index].values, width, yerr=sel[f"{index}_conf"].values,
                   capsize=2, color=colours[k % len(colours)], label=label)
        names = [str(n) for n in sub["param"].values]
        chosen = sub["selected"].values.astype(bool)
        ax.set_xticks(x, [THESIS_SYMBOLS.get(n, n) + ("*" if c else "") for n, c in zip(names, chosen)])
        for tick, c in zip(ax.get_xticklabels(), chosen):
            tick.set_fontweight("bold" if c else "normal")
        ax.axhline(0.0, color="k", lw=0.6)
        ax.set_ylim(min(-0.1, ax.get_ylim()[0]), max(1.1, ax.get_ylim()[1]))
        spread = ", ".join(_spread(sub.sel(qoi=q)) for q in qois)
        ax.set_title(f"{group}\nsd: {spread}", fontsize=9)
        ax.grid(axis="y", alpha=0.3)
    for ax in axes[:, 0]:
        ax.set_ylabel(r"total Sobol' index $S^T_i$" if index == "ST" else index)
    spare = list(axes.flat)[len(groups):]
    handles, labels = axes.flat[0].get_legend_handles_labels()
    if spare:
        spare[0].legend(handles, labels, loc="upper left", frameon=False)
        spare[0].text(0.0, 0.35, f"* selected: {screening['selected'].attrs.get('rule', '')}\n"
                                 f"bars: {int(100 * screening.attrs.get('conf_level', 0.95))} % bootstrap interval",
                      transform=spare[0].transAxes, fontsize=8, va="top")
        for ax in spare:
            ax.axis("off")
    else:
        axes.flat[0].legend(fontsize=7)
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    return fig
