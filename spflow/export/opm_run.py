"""Run OPM Flow on an exported deck and read its summary into a coreflood-format Dataset.

:func:`run_opm` runs ``flow`` (found on ``PATH``) in a directory of its own (with ``--enable-tuning=true`` when the
deck caps the time steps, :mod:`.opm_deck`), reads the unified summary (:mod:`.eclipse_summary`) and converts it
back to the core's scale with the deck's ``area_scale`` (:func:`summary_to_coreflood`): the pressure series ``dp``
(Pa) = injector BHP - producer BHP at the end of every report step, and one effluent "tube" per report step with the
oil cut, the recovery (cumulative oil / OOIP at the tube's end, OOIP = first FOIP + FOPT), the oil volume (ml at
core scale) and the polymer concentration of the produced water (ppm, tube average). The injected PV is the injected
water volume FWIT over the pore volume (OPM rounds report-step lengths to whole seconds, so time / (time of one PV)
would be off by up to 0.3 % of a step).

:func:`summary_to_series` gives the same run in the form of a :func:`spflow.simulate` result (``pv`` from 0, ``dp``
point values, effluent interval averages, ``param_*`` attrs), so that spflow's measurement chain
(:func:`spflow.synthetic.measurement.measure`: transducer, dead volume, fraction collector, noise) can turn OPM
curves into lab-like data of any tube size.
"""

from __future__ import annotations

import shutil
import subprocess
import tempfile
from pathlib import Path

import numpy as np
import xarray as xr

from spflow.core.errors import ParameterError, SpflowError
from spflow.io.format import build_coreflood

from .eclipse_summary import read_summary
from .opm_deck import OpmDeck
from .opm_tables import KG_M3_PER_PPM, PA_PER_BAR
from .opm_time_steps import TUNING_OPTION

__all__ = ["OpmNotFoundError", "OpmRunError", "flow_executable", "run_opm", "summary_to_coreflood",
           "summary_to_series", "FLOW_OPTIONS"]

#: options of every run: no rate-initialisation heuristic (it aborts polymer runs with an "infinite primary
#: variable"), no restart/grid output beyond what the summary needs, one thread, and 40 Newton iterations: with
#: PLYSHLOG OPM's polymer mass balance converges linearly (about x0.75 per iteration), and with an oleic Corey
#: exponent E2WC of 1.8, 2.14, 2.5 or 3 (measured on a polymer flood) the default 20 iterations shut the injector
#: ("cannot get converged") in the waterflood
FLOW_OPTIONS = ("--alternative-well-rate-init=false", "--enable-opm-rst-file=false", "--enable-async-ecl-output=false",
                "--threads-per-process=1", "--newton-max-iterations=40")
#: what OPM Flow prints when it gives up on a well; its summary after that is not the coreflood's
_WELL_SHUT = "will be shut"


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


def _intervals(summary: dict[str, np.ndarray], deck: OpmDeck) -> dict[str, np.ndarray]:
    """Per report step: injected PV at its end, oil cut, recovery at its end, oil (ml, core scale), produced-water
    polymer (ppm, NaN without water) and the pressure drop (Pa)."""
    for key in ("FWIT", "FOPT", "FWPT", "FOIP", "WBHP:INJ", "WBHP:PROD"):
        if key not in summary:
            raise OpmRunError(f"{deck.path}: the OPM summary has no vector {key!r}")
    fopt = summary["FOPT"]
    ooip = summary["FOIP"][0] + fopt[0]
    d_oil = np.diff(np.concatenate([[0.0], fopt]))
    d_water = np.diff(np.concatenate([[0.0], summary["FWPT"]]))
    produced = d_oil + d_water
    out = {
        "pv_end": summary["FWIT"] / deck.pore_volume_m3,
        "oil_cut": np.clip(np.where(produced > 0.0, d_oil / np.where(produced > 0.0, produced, 1.0), 0.0), 0.0, 1.0),
        "recovery": np.clip(fopt / ooip, 0.0, 1.0) if ooip > 0.0 else np.zeros_like(fopt),  # no oil: 0
        "oil_ml": np.maximum(d_oil, 0.0) / deck.area_scale * 1.0e6,
        "dp": (summary["WBHP:INJ"] - summary["WBHP:PROD"]) * PA_PER_BAR,
        "ooip_ml": ooip / deck.area_scale * 1.0e6,
    }
    if "WCPT:PROD" in summary:
        d_poly = np.diff(np.concatenate([[0.0], summary["WCPT:PROD"]]))  # kg
        with np.errstate(invalid="ignore", divide="ignore"):
            conc = np.where(d_water > 0.0, d_poly / d_water / KG_M3_PER_PPM, np.nan)
        out["c_polymer_out"] = np.maximum(conc, 0.0)
    return out


def _with_first(values: np.ndarray) -> np.ndarray:
    """``values`` preceded by its first element (the value reported at pv = 0)."""
    return np.concatenate([values[:1], values])


def summary_to_series(summary: dict[str, np.ndarray], deck: OpmDeck) -> xr.Dataset:
    """The OPM run in the form of a ``simulate()`` result: ``pv`` = 0 and the report-step ends; ``dp`` point
    values (at 0 the first step's), ``oil_cut``, ``c_polymer_out`` (0 where no water flowed), ``c_surfactant_out``
    (0) and ``salinity_out`` (the first slug's salinity: OPM carries no salt) as averages over the step ending at
    ``pv`` (at 0 the first step's), ``recovery`` at ``pv``; attrs ``param_*`` of the deck's parameters."""
    r = _intervals(summary, deck)
    pv = np.concatenate([[0.0], r["pv_end"]])
    cp = np.nan_to_num(r.get("c_polymer_out", np.zeros_like(r["dp"])), nan=0.0)
    salinity = deck.schedule.slugs[0].salinity_ppm if deck.schedule is not None else 0.0
    data = {
        "dp": ("pv", _with_first(r["dp"]), {"units": "Pa", "long_name": "pressure drop |P_inj - P_prod| (OPM Flow)"}),
        "oil_cut": ("pv", _with_first(r["oil_cut"]), {"units": "1", "long_name": "oil cut (OPM Flow)"}),
        "recovery": ("pv", np.concatenate([[0.0], r["recovery"]]), {"units": "1", "long_name": "recovery"}),
        "c_polymer_out": ("pv", _with_first(cp), {"units": "ppm", "long_name": "effluent polymer (OPM Flow)"}),
        "c_surfactant_out": ("pv", np.zeros_like(pv), {"units": "ppm", "long_name": "no surfactant in OPM"}),
        "salinity_out": ("pv", np.full_like(pv, salinity), {"units": "ppm",
                                                           "long_name": "first slug's salinity (OPM carries no salt)"}),
    }
    attrs = {f"param_{k}": v for k, v in deck.params.items()}
    attrs.update(generator="OPM Flow (spflow.export.opm_run.summary_to_series)", cells=deck.cells,
                 opm_notes="\n".join(deck.notes))
    return xr.Dataset(data, coords={"pv": ("pv", pv, {"units": "1", "long_name": "injected pore volumes"})},
                      attrs=attrs)


def summary_to_coreflood(summary: dict[str, np.ndarray], deck: OpmDeck, experiment: str | None = None):
    """The coreflood Dataset (``spflow.io.format``) of an OPM summary of ``deck`` (one tube per report step)."""
    r = _intervals(summary, deck)
    pv_end = r["pv_end"]
    pv_start = np.concatenate([[0.0], pv_end[:-1]])
    tubes = {"oil_cut": r["oil_cut"], "recovery": r["recovery"], "oil_volume": r["oil_ml"]}
    if "c_polymer_out" in r:
        tubes["c_polymer_out"] = r["c_polymer_out"]
    ooip = r["ooip_ml"]
    dp = r["dp"]
    return build_coreflood(
        experiment=experiment or deck.experiment, source=f"OPM Flow run of {deck.path.name}", pv=pv_end, dp=dp,
        tube_start=pv_start, tube_end=pv_end, tubes=tubes,
        attrs={"generator": "OPM Flow (spflow.export.opm_run)", "opm_area_scale": deck.area_scale,
               "opm_cells": deck.cells, "opm_notes": "\n".join(deck.notes),
               "pore_volume_ml": deck.pore_volume_m3 / deck.area_scale * 1.0e6,
               "ooip_ml": ooip})


def run_opm(deck: OpmDeck, workdir=None, *, form: str = "coreflood", extra_options=(), timeout_s: float = 3600.0):
    """Run ``flow`` on ``deck`` (in ``workdir``, default a temporary directory removed afterwards) and return its
    coreflood Dataset (``form="coreflood"``) or its ``simulate()``-like series (``form="series"``), with the run's
    options in attrs ``opm_flow_options`` and the deck's time-step cap in ``opm_max_step_pv`` (PV of the slug
    injected). ``extra_options`` are further command-line options of ``flow``.
    :class:`OpmNotFoundError` if ``flow`` is absent, :class:`OpmRunError` if it fails (with the
    tail of its output) or shuts a well it cannot converge."""
    if form not in ("coreflood", "series"):
        raise ParameterError(f"form must be 'coreflood' or 'series', got {form!r}")
    exe = flow_executable()
    with tempfile.TemporaryDirectory(prefix="spflow-opm-") as tmp:
        run_dir = Path(workdir) if workdir is not None else Path(tmp)
        run_dir.mkdir(parents=True, exist_ok=True)
        deck_copy = run_dir / deck.path.name
        if deck_copy.resolve() != deck.path.resolve():
            shutil.copyfile(deck.path, deck_copy)
        tuning = (TUNING_OPTION,) if deck.max_step_pv is not None else ()
        cmd = [exe, deck_copy.name, "--output-dir=.", *FLOW_OPTIONS, *tuning, *extra_options]
        try:
            proc = subprocess.run(cmd, cwd=run_dir, capture_output=True, text=True, timeout=timeout_s)
        except subprocess.TimeoutExpired:
            raise OpmRunError(f"OPM Flow did not finish {deck.path} within {timeout_s:g} s") from None
        base = run_dir / deck_copy.stem
        smspec, unsmry = base.with_suffix(".SMSPEC"), base.with_suffix(".UNSMRY")
        if proc.returncode != 0 or not unsmry.is_file():
            tail = "\n".join((proc.stdout + proc.stderr).strip().splitlines()[-15:])
            raise OpmRunError(f"OPM Flow failed on {deck.path} (exit code {proc.returncode}):\n{tail}")
        shut = [line.strip() for line in proc.stdout.splitlines() if _WELL_SHUT in line]
        if shut:
            raise OpmRunError(f"OPM Flow shut a well on {deck.path} ({shut[0]!r}): its rates and pressures after "
                              f"that are not the coreflood's; options of the run: {' '.join(cmd[3:])}")
        summary = read_summary(smspec, unsmry)
        out = summary_to_coreflood(summary, deck) if form == "coreflood" else summary_to_series(summary, deck)
        out.attrs["opm_flow_options"] = " ".join(cmd[3:])
        out.attrs["opm_max_step_pv"] = deck.max_step_pv if deck.max_step_pv is not None else "none (OPM's own steps)"
        return out
