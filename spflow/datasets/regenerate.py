"""Regenerate a bundled dataset from the truth file — used by ``scripts/make_bundled_data.py`` and the tests.

Reading the truth is what makes this module off-limits to pipeline code (see ``truth/truth.toml``).
"""

from __future__ import annotations

import tomllib

import xarray as xr

from spflow.synthetic import NoiseModel, make_coreflood

from . import NAMES, truth_path

__all__ = ["read_truth", "regenerate"]


def read_truth() -> dict:
    """The parsed truth file."""
    with open(truth_path(), "rb") as fh:
        return tomllib.load(fh)


def regenerate(name: str) -> xr.Dataset:
    """The bundled dataset ``name`` recomputed from the truth's parameters, effects, noise and seed."""
    key = str(name).strip().upper()
    if key not in NAMES:
        raise ValueError(f"unknown bundled dataset {name!r}; known: {', '.join(NAMES)}")
    truth = read_truth()
    ds = make_coreflood(key, truth["params"], effects=truth["effects"], noise=NoiseModel.from_mapping(truth["noise"]),
                        seed=truth["experiments"][key]["seed"], cells=truth["simulation"]["cells"],
                        pv_step=truth["simulation"]["pv_step"], experiment=key)
    ds.attrs["source"] = "bundled lab-like dataset (spflow.datasets), synthetic: generated from a withheld truth"
    return ds
