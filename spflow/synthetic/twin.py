"""The synthetic-twin generator: a forward simulation seen through a lab's measurement chain.

``make_coreflood`` runs :func:`spflow.plugins.forward.simulate.simulate` on a fine PV grid with the given
(truth) parameters and effects, then applies :func:`spflow.synthetic.measurement.measure`. The result has the
format of the bundled datasets and of loaded lab files (:mod:`spflow.io.format`) and is reproducible bit for bit
from ``seed`` (the simulator is deterministic).
"""

from __future__ import annotations

import numbers
from pathlib import Path

import xarray as xr

from spflow.core.version import __version__
from spflow.io.format import schedule_json
from spflow.plugins.forward.schedule import as_schedule
from spflow.plugins.forward.simulate import simulate

from .measurement import measure
from .noise_model import NoiseModel

__all__ = ["make_coreflood"]


def write_twins(directory, truth_params, *, noise, seed, cells=100, experiments=("BCF1", "BCF2", "BCF3")) -> list[str]:
    """Twins of the bundled corefloods ``experiments`` as ``<directory>/twin_<name>.nc`` (the k-th with noise seed
    ``seed + k``), for pipelines that take coreflood files; returns the paths."""
    paths = []
    for k, experiment in enumerate(experiments):
        path = Path(directory) / f"twin_{experiment}.nc"
        make_coreflood(experiment, truth_params, noise=noise, seed=seed + k, cells=cells).to_netcdf(path)
        paths.append(str(path))
    return paths


def make_coreflood(schedule, truth_params=None, *, effects=None, noise=None, seed=0, cells=100, pv_step=0.005,
                   experiment=None) -> xr.Dataset:
    """A lab-like coreflood Dataset (format of :mod:`spflow.io.format`).

    Parameters
    ----------
    schedule: a Table 2.5 name (``"BCF1"``..) or anything ``as_schedule`` accepts.
    truth_params: forward-model parameters (UTCHEM names); ``None`` means the defaults.
    effects: effect strengths (``{name: strength}``), e.g. ``{"kinetic_adsorption": 20}``; ``None``: defaults.
    noise: a :class:`NoiseModel`; ``None`` means ``NoiseModel()`` (documented defaults).
    seed: integer in [0, 2**63) seeding the measurement noise.
    cells, pv_step: grid cells and output PV step of the underlying simulation.
    experiment: name stored in the ``experiment`` attr (default: the schedule's name).
    """
    if noise is None:
        noise = NoiseModel()
    if not isinstance(noise, NoiseModel):
        raise ValueError(f"noise must be a NoiseModel or None, got {type(noise).__name__}")
    if isinstance(seed, bool) or not isinstance(seed, numbers.Integral) or not 0 <= seed < 2**63:
        raise ValueError(f"seed must be an integer in [0, 2**63), got {seed!r}")
    sched = as_schedule(schedule)
    if sched.total_pv < noise.tube_pv or sched.total_pv < noise.pressure_interval_pv:
        raise ValueError(f"noise.tube_pv = {noise.tube_pv!r} and noise.pressure_interval_pv = "
                         f"{noise.pressure_interval_pv!r} must not exceed the injected {sched.total_pv!r} PV")
    clean = simulate(sched, truth_params, cells=cells, effects=effects, pv_step=pv_step)
    ds = measure(clean, noise, int(seed), experiment=experiment or sched.name,
                 source="synthetic twin (spflow.synthetic.make_coreflood)", schedule=schedule_json(sched))
    ds.attrs.update(generator="spflow.synthetic.make_coreflood", seed=int(seed), spflow_version=__version__,
                    simulation_cells=int(cells), simulation_pv_step=float(pv_step))
    return ds
