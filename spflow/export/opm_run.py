"""Run OPM Flow on an exported deck and read its summary into a coreflood-format Dataset.

:func:`run_opm` runs ``flow`` (found on ``PATH``) in a directory of its own, reads the unified summary
(:mod:`.eclipse_summary`) and converts it back to the core's scale with the deck's ``area_scale``
(:func:`summary_to_coreflood`): the pressure series ``dp`` (Pa) = injector BHP - producer BHP at the end of every
report step, and one effluent "tube" per report step with the oil cut, the recovery (cumulative oil / OOIP at the
tube's end, OOIP = first FOIP + FOPT), the oil volume (ml at core scale) and the polymer concentration of the
produced water (ppm, tube average). The injected PV is the injected water volume FWIT over the pore volume (OPM
rounds report-step lengths to whole seconds, so time / (time of one PV) would be off by up to 0.3 % of a step).
"""

from __future__ import annotations

import shutil
import subprocess
import tempfile
from pathlib import Path

import numpy as np

from spflow.core.errors import SpflowError
from spflow.io.format import build_coreflood

from .eclipse_summary import read_summary
from .opm_deck import OpmDeck
from .opm_tables import KG_M3_PER_PPM, PA_PER_BAR

__all__ = ["OpmNotFoundError", "OpmRunError", "flow_executable", "run_opm", "summary_to_coreflood",
           "FLOW_OPTIONS"]

#: options of every run: no rate-initialisation heuristic (it aborts polymer runs with an "infinite primary
#: variable"), no restart/grid output beyond what the summary needs, one thread.
FLOW_OPTIONS = ("--alternative-well-rate-init=false", "--enable-opm-rst-file=false", "--enable-async-ecl-output=false",
                "--threads-per-process=1")


class OpmNotFoundError(SpflowError):
    """The OPM Flow executable ``flow`` is not on PATH."""


class OpmRunError(SpflowError):
    """OPM Flow failed on a deck."""


def flow_executable() -> str:
    """Path of ``flow`` on PATH, or :class:`OpmNotFoundError` saying how to install it."""
    exe = shutil.which("flow")
    if exe is None:
        raise OpmNotFoundError("OPM Flow ('flow') is not on PATH; install it, e.g. on Debian/Ubuntu "
                               "`apt-get install libopm-simulators-bin` (package 2022.10)")
    return exe


def summary_to_coreflood(summary: dict[str, np.ndarray], deck: OpmDeck, experiment: str | None = None):
    """The coreflood Dataset (``spflow.io.format``) of an OPM summary of ``deck`` (one row per report step)."""
    for key in ("FWIT", "FOPT", "FWPT", "FOIP", "WBHP:INJ", "WBHP:PROD"):
        if key not in summary:
            raise OpmRunError(f"{deck.path}: the OPM summary has no vector {key!r}")
    pv_end = summary["FWIT"] / deck.pore_volume_m3
    pv_start = np.concatenate([[0.0], pv_end[:-1]])
    fopt = summary["FOPT"]
    fwpt = summary["FWPT"]
    ooip = summary["FOIP"][0] + fopt[0]
    d_oil = np.diff(np.concatenate([[0.0], fopt]))
    d_water = np.diff(np.concatenate([[0.0], fwpt]))
    produced = d_oil + d_water
    oil_cut = np.where(produced > 0.0, d_oil / np.where(produced > 0.0, produced, 1.0), 0.0)
    tubes = {
        "oil_cut": np.clip(oil_cut, 0.0, 1.0),
        "recovery": np.clip(fopt / ooip, 0.0, 1.0),
        "oil_volume": np.maximum(d_oil, 0.0) / deck.area_scale * 1.0e6,
    }
    if "WCPT:PROD" in summary:
        d_poly = np.diff(np.concatenate([[0.0], summary["WCPT:PROD"]]))  # kg
        with np.errstate(invalid="ignore", divide="ignore"):
            conc = np.where(d_water > 0.0, d_poly / d_water / KG_M3_PER_PPM, np.nan)
        tubes["c_polymer_out"] = np.maximum(conc, 0.0)
    dp = (summary["WBHP:INJ"] - summary["WBHP:PROD"]) * PA_PER_BAR
    return build_coreflood(
        experiment=experiment or deck.experiment, source=f"OPM Flow run of {deck.path.name}", pv=pv_end, dp=dp,
        tube_start=pv_start, tube_end=pv_end, tubes=tubes,
        attrs={"generator": "OPM Flow (spflow.export.opm_run)", "opm_area_scale": deck.area_scale,
               "opm_cells": deck.cells, "opm_notes": "\n".join(deck.notes),
               "pore_volume_ml": deck.pore_volume_m3 / deck.area_scale * 1.0e6,
               "ooip_ml": ooip / deck.area_scale * 1.0e6})


def run_opm(deck: OpmDeck, workdir=None, *, extra_options=(), timeout_s: float = 3600.0):
    """Run ``flow`` on ``deck`` (in ``workdir``, default a temporary directory removed afterwards) and return its
    coreflood Dataset. :class:`OpmNotFoundError` if ``flow`` is absent, :class:`OpmRunError` if it fails (with the
    tail of its output)."""
    exe = flow_executable()
    with tempfile.TemporaryDirectory(prefix="spflow-opm-") as tmp:
        run_dir = Path(workdir) if workdir is not None else Path(tmp)
        run_dir.mkdir(parents=True, exist_ok=True)
        deck_copy = run_dir / deck.path.name
        if deck_copy.resolve() != deck.path.resolve():
            shutil.copyfile(deck.path, deck_copy)
        cmd = [exe, deck_copy.name, "--output-dir=.", *FLOW_OPTIONS, *extra_options]
        try:
            proc = subprocess.run(cmd, cwd=run_dir, capture_output=True, text=True, timeout=timeout_s)
        except subprocess.TimeoutExpired:
            raise OpmRunError(f"OPM Flow did not finish {deck.path} within {timeout_s:g} s") from None
        base = run_dir / deck_copy.stem
        smspec, unsmry = base.with_suffix(".SMSPEC"), base.with_suffix(".UNSMRY")
        if proc.returncode != 0 or not unsmry.is_file():
            tail = "\n".join((proc.stdout + proc.stderr).strip().splitlines()[-15:])
            raise OpmRunError(f"OPM Flow failed on {deck.path} (exit code {proc.returncode}):\n{tail}")
        return summary_to_coreflood(read_summary(smspec, unsmry), deck)
