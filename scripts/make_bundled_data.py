"""Regenerate the bundled datasets spflow/datasets/BCF{1,2,3}.nc from the truth file, deterministically.

    .venv/bin/python scripts/make_bundled_data.py            # write the files and print the sim-to-real gap
    .venv/bin/python scripts/make_bundled_data.py --check    # only verify the files equal a regeneration

The gap report compares each bundled dataset with the base model (withheld mechanisms off) seen through the
deterministic part of the same measurement chain (same transducer and tube grids, same dead volume, no random
error, offset or drift): (a) at the default parameters, (b) at the truth parameters — the part of the gap due to
the withheld mechanisms alone — and (c) the full truth model, whose difference is measurement noise only.
"""

from __future__ import annotations

import argparse
import sys

import numpy as np
import xarray as xr

from spflow.datasets import NAMES, path
from spflow.datasets.regenerate import read_truth, regenerate
from spflow.synthetic import NoiseModel, make_coreflood

QOIS = ("dp", "oil_cut", "recovery")


def _rms(a: xr.Dataset, b: xr.Dataset) -> dict[str, float]:
    return {q: float(np.sqrt(np.mean((a[q].values - b[q].values) ** 2))) for q in QOIS}


def gap_report(name: str, bundled: xr.Dataset) -> dict[str, dict[str, float]]:
    """RMS differences of dp (Pa), oil cut and recovery between ``bundled`` and three noise-free references."""
    truth = read_truth()
    noise = NoiseModel.from_mapping(truth["noise"])
    exact = NoiseModel.exact(pressure_interval_pv=noise.pressure_interval_pv, tube_pv=noise.tube_pv,
                             dead_volume_ml=noise.dead_volume_ml)
    sim = dict(cells=truth["simulation"]["cells"], pv_step=truth["simulation"]["pv_step"], noise=exact)
    base_off = {k: 0.0 for k in truth["effects"]}
    return {
        "base model, default parameters": _rms(bundled, make_coreflood(name, None, effects=base_off, **sim)),
        "base model, truth parameters": _rms(bundled, make_coreflood(name, truth["params"], effects=base_off, **sim)),
        "truth model (noise only)": _rms(bundled, make_coreflood(name, truth["params"], effects=truth["effects"],
                                                                 **sim)),
    }


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--check", action="store_true", help="verify the files instead of writing them")
    args = parser.parse_args(argv)
    status, rows = 0, []
    for name in NAMES:
        ds = regenerate(name)
        if args.check:
            with xr.open_dataset(path(name)) as stored:
                same = all(np.array_equal(stored[v].values, ds[v].values, equal_nan=True) for v in ds.variables)
            print(f"{name}: {'identical' if same else 'DIFFERS'}")
            status |= not same
            continue
        ds.to_netcdf(path(name), engine="netcdf4")
        print(f"wrote {path(name)}")
        rows += [f"| {name} | {label} | {rms['dp']:.0f} | {rms['oil_cut']:.4f} | {rms['recovery']:.4f} |"
                 for label, rms in gap_report(name, ds).items()]
    if rows:
        print("\n| data | RMS vs | dp (Pa) | oil cut (-) | recovery (-) |\n|---|---|---|---|---|")
        print("\n".join(rows))
    return status


if __name__ == "__main__":
    sys.exit(main())
