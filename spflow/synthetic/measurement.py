"""Apply the lab's measurement chain to a clean simulation: transducer, outlet dead volume, fraction collector.

``measure(clean, noise, seed)`` turns a Dataset of :func:`spflow.plugins.forward.simulate.simulate` (fine
``pv`` grid; ``dp`` point values, effluent quantities interval averages) into the coreflood format of
:mod:`spflow.io.format`:

* ``dp`` on the transducer grid: :func:`spflow.synthetic.transducer.read_pressure`;
* tubes (:mod:`spflow.synthetic.fraction_collector`) of the effluent delayed by the outlet lines
  (:mod:`spflow.synthetic.dead_volume`, lines initially full of the initial aqueous effluent, no oil):
  ``oil_volume`` = reading of the true tube oil (ml); ``oil_cut = oil_volume / tube volume``;
  ``recovery = cumsum(oil_volume) / OOIP`` at the tube ends — computed from readings, as a lab does;
  assays: polymer and salinity averaged over the tube's water (weights ``1 - oil cut``), surfactant over the whole
  tube (the simulator reports it per total volume), each times ``1 + concentration_relative * N(0, 1)``, kept >= 0.
  A tube without water has no polymer or salinity assay: NaN (``empty_tubes="missing"``, lab data), or the
  water-weighted average's limit as the tube's water goes to zero (``empty_tubes="limit"``, predictions compared
  with data): the simulator's own effluent series averaged over the tube -- it reports, where no water flows, no
  polymer and the salinity of the outlet cell's water.

Three independent random streams are spawned from ``seed`` (``numpy.random.SeedSequence(seed).spawn(3)``):
pressure, oil readings, assays — so changing one part of the model does not reshuffle the others.
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from spflow.io.format import build_coreflood
from spflow.io.metadata import CORE_ATTRS, core_unit

from .core_volumes import ooip_ml, pore_volume_ml
from .dead_volume import delay
from .fraction_collector import read_oil_volumes, tube_amounts, tube_edges
from .noise_model import NoiseModel
from .transducer import read_pressure

__all__ = ["measure"]

#: assay -> whether it is averaged over the tube's water (else over the whole tube)
_ASSAYS = (("c_polymer_out", True), ("c_surfactant_out", False), ("salinity_out", True))
_EMPTY_TUBES = ("missing", "limit")


def measure(clean: xr.Dataset, noise: NoiseModel, seed: int, *, experiment: str, source: str,
            schedule: str | None = None, empty_tubes: str = "missing") -> xr.Dataset:
    """Lab-like measurements of ``clean`` (a ``simulate`` result) under ``noise``, reproducible from ``seed``.

    ``schedule`` is the JSON text stored in the ``schedule`` attr (see :func:`spflow.io.format.schedule_json`);
    ``empty_tubes`` (``"missing"`` or ``"limit"``) the per-water assays of tubes without water (module docstring).
    """
    if not isinstance(noise, NoiseModel):
        raise ValueError(f"noise must be a NoiseModel, got {type(noise).__name__}")
    if empty_tubes not in _EMPTY_TUBES:
        raise ValueError(f"empty_tubes must be one of {list(_EMPTY_TUBES)}, got {empty_tubes!r}")
    missing = [v for v in ("dp", "oil_cut", *(name for name, _ in _ASSAYS)) if v not in clean]
    missing += [f"param_{p}" for p in CORE_ATTRS.values() if f"param_{p}" not in clean.attrs]
    if missing or "pv" not in clean.coords:
        raise ValueError(f"clean must be a simulate() result (coordinate 'pv'); missing {missing or ['pv']}")
    params = {p: clean.attrs[f"param_{p}"] for p in CORE_ATTRS.values()}
    pv_ml, oil_in_place_ml = pore_volume_ml(params), ooip_ml(params)
    rng_pressure, rng_oil, rng_assay = (np.random.default_rng(s) for s in np.random.SeedSequence(seed).spawn(3))

    pv = clean["pv"].values
    t, dp = read_pressure(pv, clean["dp"].values, noise, rng_pressure)

    edges = tube_edges(float(pv[-1]), noise.tube_pv)
    v_dead = noise.dead_volume_ml / pv_ml
    oil_cut = clean["oil_cut"].values
    water = 1.0 - oil_cut

    def collected(values, fill):
        return tube_amounts(*delay(pv, values, v_dead, fill), edges)

    tube_ml = noise.tube_pv * pv_ml
    oil_ml = read_oil_volumes(collected(oil_cut, 0.0) * pv_ml, tube_ml, noise.oil_resolution_ml, rng_oil)
    tubes = {"oil_cut": oil_ml / tube_ml, "recovery": np.cumsum(oil_ml) / oil_in_place_ml, "oil_volume": oil_ml}

    water_pv = collected(water, 1.0)
    has_water = water_pv > 1.0e-12 * noise.tube_pv
    assay_error = rng_assay.standard_normal((len(_ASSAYS), edges.size - 1))
    for row, (name, per_water) in enumerate(_ASSAYS):
        c = clean[name].values
        if per_water:
            amount = collected(c * water, c[0])
            empty = np.nan if empty_tubes == "missing" else collected(c, c[0]) / noise.tube_pv
            mean = np.where(has_water, amount / np.where(has_water, water_pv, 1.0), empty)
        else:
            mean = collected(c, c[0]) / noise.tube_pv
        tubes[name] = np.maximum(mean * (1.0 + noise.concentration_relative * assay_error[row]), 0.0)

    attrs = {"pore_volume_ml": pv_ml, "ooip_ml": oil_in_place_ml, "dead_volume_pv": v_dead}
    for name, p in CORE_ATTRS.items():  # the lab-known core data, with units (spflow.io.metadata)
        attrs.update({name: float(params[p]), f"{name}_units": core_unit(name)})
    attrs.update(noise.to_attrs())
    if schedule is not None:
        attrs["schedule"] = schedule
    return build_coreflood(experiment=experiment, source=source, pv=t, dp=dp, tube_start=edges[:-1],
                           tube_end=edges[1:], tubes=tubes, attrs=attrs)
