"""The ``observations`` stage: measured corefloods on the simulator's output grid, so a misfit is a plain difference.

A lab measures on two grids (transducer points ``pv``, effluent tubes ``pv_tube``, see :mod:`spflow.io.format`);
the simulator reports on ``0, Δ, 2Δ, ...`` (:func:`~spflow.plugins.forward.simulate.output_grid`) with the same
sampling conventions the tubes have. Each variable is carried over with its own convention, never blindly
interpolated:

* ``dp`` (point value) — linear interpolation in the transducer series, never across a rate step (Δp jumps there):
  a point between two rate steps takes only the samples between them, a point at a rate step (the end of a slug)
  the samples up to it (the left limit, as the simulator records a slug end), extrapolated linearly by at most a
  quarter of the samples' median spacing (a reading time-stamped just before the step); farther, the point has no
  data (NaN);
* ``recovery`` (cumulative, reported at ``pv_tube_end``) — linear interpolation in ``pv_tube_end``;
* ``oil_cut``, ``c_polymer_out``, ``c_surfactant_out``, ``salinity_out`` (tube averages) — the volume average of the
  tubes over the simulator's interval ``(pv - Δ, pv]``, which is what the simulator reports there.

The effluent variables (``recovery`` and the tube averages) are first moved back by the outlet dead volume the
coreflood records (``dead_volume="correct"``, the default): a collector behind a line of ``v = noise_dead_volume_ml /
pore_volume_ml`` PV receives the core's effluent of ``(a, b]`` during ``(a + v, b + v]`` (plug flow in the line,
:mod:`spflow.synthetic.dead_volume`), so a tube ``(a, b]`` holds the core outlet's ``(a - v, b - v]`` and the
simulator, which reports at the core outlet, compares with it directly. Tubes that hold line fill (``a < v``) are
dropped from the averaged variables; cumulative recovery at ``b - v`` is exact. The shift used per experiment is the
output's ``dead_volume_pv`` (0 where the coreflood records no dead volume or pore volume: nothing to correct);
``dead_volume="keep"`` compares the readings as measured.

Grid points the data does not cover (before the first sample, after the last tube, or intervals touching a tube
without a value) are NaN. The output has dims (``experiment``, ``pv``) like one sample of the ``forward`` stage's
responses, with each experiment's ``total_pv``. Its JSON attr ``coreflood_attrs`` maps each experiment to its
coreflood's own attrs (schedule, core data, the ``noise_*`` measurement model when the file has one, provenance), so a
later stage can rebuild the lab's error model (:func:`spflow.plugins.gap.observed.observed_experiment`).
"""

from __future__ import annotations

import json
import sys

import numpy as np
import xarray as xr

from spflow.core.errors import ParameterError
from spflow.core.hashing import canonical_hash
from spflow.core.params import Param
from spflow.core.schema import DatasetSchema, Variable
from spflow.core.stage import Stage, StageContext
from spflow.io.observed_source import load_observed, source_label
from spflow.io.format import VARIABLES
from spflow.plugins.forward.schedule import as_schedule
from spflow.plugins.forward.run_arguments import common_grid, output_grid

__all__ = ["Observations", "OBSERVATIONS", "at_core_outlet", "dead_volume_pv", "on_simulator_grid"]

_AVERAGED = ("oil_cut", "c_polymer_out", "c_surfactant_out", "salinity_out")
_ALLOWED = ("dp", "recovery", *_AVERAGED)

#: Schema of measured data on the simulator grid.
OBSERVATIONS = DatasetSchema(
    dims=("experiment", "pv"),
    variables={"total_pv": Variable(("experiment",), units="1", long_name="pore volumes injected in the coreflood")},
    doc="measured corefloods on the simulator's output grid",
)


_OVERLAP_ELEMENTS = 2_000_000
"""Largest windows x tubes overlap block of `_tube_average` (float64 and bool: about 18 MB)."""


def _tube_average(ds: xr.Dataset, name: str, grid: np.ndarray, step: float) -> np.ndarray:
    """Volume average of tube values over ``(pv - step, pv]`` for each grid point (NaN where not covered)."""
    start, end = ds["pv_tube_start"].values, ds["pv_tube_end"].values
    values = ds[name].values
    out = np.full(grid.size, np.nan)
    lo = np.maximum(grid - step, 0.0)
    covered = np.flatnonzero((grid > 0.0) & (lo >= start[0] - 1e-9) & (grid <= end[-1] + 1e-9))
    # windows in blocks, so the windows x tubes overlap matrix stays below _OVERLAP_ELEMENTS whatever the grid
    rows = max(1, _OVERLAP_ELEMENTS // max(start.size, 1))
    for block in np.array_split(covered, max(1, -(-covered.size // rows))):
        # overlap of every window with every tube, one row per window (elementwise, as a loop would compute it)
        overlap = np.clip(np.minimum(end, grid[block, None]) - np.maximum(start, lo[block, None]), 0.0, None)
        used = overlap > 1e-12
        complete = ~(used & np.isnan(values)).any(axis=1)
        for k, row, mask in zip(block[complete], overlap[complete], used[complete]):
            # each window's sums over its own tubes only, in tube order (bit for bit the per-window sums)
            out[k] = float((values[mask] * row[mask]).sum() / row[mask].sum())
    return out


def _json_attrs(attrs) -> dict:
    """A coreflood's attrs as JSON values (numpy scalars and arrays to Python numbers and lists)."""
    return {k: v.tolist() if isinstance(v, (np.generic, np.ndarray)) else v for k, v in attrs.items()}


def _point(x: np.ndarray, y: np.ndarray, grid: np.ndarray, steps=()) -> np.ndarray:
    """Linear interpolation of a point series, NaN outside its span; with rate ``steps`` (PV), piecewise between
    them (module docstring)."""
    keep = np.isfinite(y)
    x, y = x[keep], y[keep]
    if not x.size:
        return np.full(grid.size, np.nan)
    if len(steps) == 0:
        return np.interp(grid, x, y, left=np.nan, right=np.nan)
    # a point within rounding of a step belongs to the slug the step ends
    bounds = np.asarray(steps, dtype=np.float64) + 1.0e-9 * max(1.0, float(grid[-1]))
    reach = 0.25 * float(np.median(np.diff(x))) * (1.0 + 1.0e-9) if x.size > 1 else 0.0
    of_x, of_grid = np.searchsorted(bounds, x), np.searchsorted(bounds, grid)
    out = np.full(grid.size, np.nan)
    for k in np.unique(of_grid):
        xs, ys = x[of_x == k], y[of_x == k]
        at = of_grid == k
        if xs.size == 0:
            continue
        g = grid[at]
        v = np.interp(g, xs, ys, left=np.nan, right=np.nan)
        if xs.size > 1:
            slope_lo, slope_hi = (ys[1] - ys[0]) / (xs[1] - xs[0]), (ys[-1] - ys[-2]) / (xs[-1] - xs[-2])
            lo, hi = (g < xs[0]) & (xs[0] - g <= reach), (g > xs[-1]) & (g - xs[-1] <= reach)
            v[lo] = ys[0] + slope_lo * (g[lo] - xs[0])
            v[hi] = ys[-1] + slope_hi * (g[hi] - xs[-1])
        out[at] = v
    return out


def dead_volume_pv(ds: xr.Dataset) -> float:
    """The outlet dead volume a coreflood records, in PV (``noise_dead_volume_ml / pore_volume_ml``); 0 when it
    records no dead volume or no pore volume."""
    volume, pore = ds.attrs.get("noise_dead_volume_ml"), ds.attrs.get("pore_volume_ml")
    if volume is None or pore is None:
        return 0.0
    return float(volume) / float(pore)


def at_core_outlet(ds: xr.Dataset, shift: float) -> xr.Dataset:
    """``ds`` with its tubes moved back by ``shift`` PV (the outlet dead volume, module docstring): tube bounds
    ``- shift``; averaged variables of tubes that start before the core's effluent reaches the collector are NaN,
    recovery at tube ends at or before 0 PV is NaN."""
    if shift == 0.0 or "pv_tube_end" not in ds.coords:
        return ds
    out = ds.assign_coords(pv_tube_start=ds["pv_tube_start"] - shift, pv_tube_end=ds["pv_tube_end"] - shift)
    flushing = out["pv_tube_start"].values < -1e-12
    for name in _AVERAGED:
        if name in out:
            out[name] = out[name].where(~flushing)
    if "recovery" in out:
        out["recovery"] = out["recovery"].where(out["pv_tube_end"] > 1e-12)
    return out


def on_simulator_grid(ds: xr.Dataset, variables: list[str], grid: np.ndarray, step: float,
                      rate_steps=()) -> dict[str, np.ndarray]:
    """Each requested variable of coreflood ``ds`` on ``grid`` (spacing ``step``), NaN where it has no data;
    ``dp`` is not interpolated across the ``rate_steps`` (PV; :meth:`Schedule.rate_steps_pv`)."""
    out = {}
    for name in variables:
        if name not in ds:
            out[name] = np.full(grid.size, np.nan)
        elif name == "dp":
            out[name] = _point(ds["pv"].values, ds["dp"].values, grid, rate_steps)
        elif name == "recovery":
            out[name] = _point(ds["pv_tube_end"].values, ds["recovery"].values, grid)
        else:
            out[name] = _tube_average(ds, name, grid, step)
    return out


class Observations(Stage):
    name = "observations"
    version = "5"
    description = "measured corefloods (bundled names or files) on the simulator's output grid"
    output = OBSERVATIONS
    params = {
        "experiments": Param(list, ["BCF1", "BCF2", "BCF3"],
                             doc="bundled names (BCF1-3), paths of coreflood files (.nc/.csv) or study experiments' "
                                 "{name, data, sha256, attrs} mappings"),
        "variables": Param(list, ["dp", "oil_cut", "recovery"], choices=list(_ALLOWED), doc="measured variables"),
        "pv_step": Param(float, 0.1, bounds=(1e-4, 1.0), unit="PV", doc="simulator output grid spacing"),
        "dead_volume": Param(str, "correct", choices=["correct", "keep"],
                             doc="correct: effluent series moved back by the outlet dead volume each coreflood records "
                                 "(to the core outlet the simulator reports at); keep: as measured"),
    }

    def _load(self) -> list[xr.Dataset]:
        """The corefloods, read once per stage instance (the fingerprint and ``run`` share them)."""
        if getattr(self, "_data", None) is None:
            data = []
            for source in self.params["experiments"]:
                try:
                    ds = load_observed(source)
                except (ValueError, OSError) as exc:
                    raise ParameterError(f"stage 'observations' parameter 'experiments': {source_label(source)!r}: "
                                         f"{exc}") from None
                if "schedule" not in ds.attrs:
                    raise ParameterError(f"stage 'observations': coreflood {source_label(source)!r} has no 'schedule' "
                                         "attr, so its total PV is unknown; load it with a schedule")
                data.append(ds)
            self._data = data
        return self._data

    def fingerprint(self) -> str:
        return canonical_hash(self._load())

    def run(self, ctx: StageContext) -> xr.Dataset:
        data = self._load()
        names = [str(ds.attrs["experiment"]) for ds in data]
        if len(set(names)) != len(names):
            raise ParameterError(f"stage 'observations': experiments must be distinct, got {names}")
        step, variables = self.params["pv_step"], list(self.params["variables"])
        schedules = [as_schedule(json.loads(ds.attrs["schedule"])) for ds in data]
        totals = np.array([sched.total_pv for sched in schedules])
        grid, positions = common_grid(totals, step)
        values = {name: np.full((len(data), grid.size), np.nan) for name in variables}
        shifts = np.array([dead_volume_pv(ds) if self.params["dead_volume"] == "correct" else 0.0 for ds in data])
        steps = [sched.rate_steps_pv() for sched in schedules]
        for i, ds in enumerate(data):
            own = output_grid(float(totals[i]), step)
            for name, series in on_simulator_grid(at_core_outlet(ds, float(shifts[i])), variables, own, step,
                                                  steps[i]).items():
                values[name][i, positions[i]] = series
            if steps[i].size and "dp" in variables and ctx.verbose:
                print(f"[{ctx.node}] {names[i]}: dp not interpolated across its rate steps at "
                      f"{', '.join(f'{x:g}' for x in steps[i])} PV (the left limit at each; attr dp_rate_steps_pv)",
                      file=sys.stderr, flush=True)
        out = xr.Dataset(
            {name: (("experiment", "pv"), v, {"units": VARIABLES[name][1], "long_name": f"observed {VARIABLES[name][2]}"
                                                                            " on the simulator grid"})
             for name, v in values.items()}
            | {"total_pv": ("experiment", totals, {"units": "1"}),
               "dead_volume_pv": ("experiment", shifts, {"units": "1", "long_name": "outlet dead volume the "
                                                          "effluent series were moved back by"})},
            coords={"experiment": ("experiment", names, {"long_name": "coreflood"}),
                    "pv": ("pv", grid, {"units": "1", "long_name": "injected pore volumes"})},
            attrs={"pv_step": step, "sources": " ".join(map(source_label, self.params["experiments"])),
                   "coreflood_attrs": json.dumps({n: _json_attrs(ds.attrs) for n, ds in zip(names, data)}),
                   "dp_rate_steps_pv": json.dumps({n: st.tolist() for n, st in zip(names, steps)})},
        )
        return out
