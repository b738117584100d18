"""Executor overhead and canonical-hashing throughput (a benchmark, not a test).

1. A 50-node DAG of trivial stages, all cache hits: wall time of ``spflow.run`` (target < 1 s). Baseline in the same
   run: the time to load the same 50 results with plain ``xarray.open_dataset`` (the unavoidable I/O).
2. Canonical hashing of a ~100 MB Dataset: MB/s of ``canonical_hash`` vs ``hashlib.sha256`` over the raw bytes.

Run: ``python benchmarks/bench_executor.py``
"""

from __future__ import annotations

import hashlib
import statistics
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import xarray as xr

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests" / "core"))

import spflow  # noqa: E402
import toy_stages  # noqa: E402
from spflow.core.hashing import canonical_hash  # noqa: E402


def _dag(n: int = 50) -> spflow.Pipeline:
    p = spflow.Pipeline("bench50")
    p.add("n0", "toy_source", params={"n": 10})
    for i in range(1, n):
        p.add(f"n{i}", "toy_scale", inputs={"data": f"n{(i - 1) // 2}"}, params={"factor": 1.0 + i / n})
    return p


def bench_cache_hits(repeats: int = 5) -> tuple[float, float]:
    spflow.register_plugin(toy_stages, name="toy_stages")
    with tempfile.TemporaryDirectory() as tmp:
        first = spflow.run(_dag(), cache=tmp)
        assert len(first.executed) == 50
        times, baseline = [], []
        for _ in range(repeats):
            t0 = time.perf_counter()
            result = spflow.run(_dag(), cache=tmp)
            for node in result:  # load every output, as a user reading all results would
                result[node]
            times.append(time.perf_counter() - t0)
            assert result.executed == []
            t0 = time.perf_counter()
            for path in Path(tmp, "objects").glob("*/*/data.nc"):
                with xr.open_dataset(path) as ds:
                    ds.load()
            baseline.append(time.perf_counter() - t0)
    spflow.unregister_plugin("toy_stages")
    return statistics.median(times), statistics.median(baseline)


def bench_hashing(megabytes: int = 100) -> tuple[float, float]:
    n = megabytes * 1024 * 1024 // 8 // 4
    rng = np.random.default_rng(0)
    ds = xr.Dataset({f"v{i}": ("x", rng.random(n), {"units": "Pa"}) for i in range(4)})
    size_mb = sum(v.nbytes for v in ds.data_vars.values()) / 2**20
    t0 = time.perf_counter()
    canonical_hash(ds)
    t_canon = time.perf_counter() - t0
    raw = [ds[v].values for v in ds.data_vars]
    t0 = time.perf_counter()
    h = hashlib.sha256()
    for arr in raw:
        h.update(arr)  # buffer protocol: no copy
    t_raw = time.perf_counter() - t0
    return size_mb / t_canon, size_mb / t_raw


def main() -> None:
    hits, base = bench_cache_hits()
    canon, raw = bench_hashing()
    print("| benchmark | spflow | baseline | ratio (spflow/baseline) | target |")
    print("|---|---|---|---|---|")
    print(f"| 50-node DAG, all cache hits (s) | {hits:.3f} | {base:.3f} (bare netCDF loads) | {hits / base:.2f} | < 1 s |")
    print(f"| canonical hash of 100 MB Dataset (MB/s) | {canon:.0f} | {raw:.0f} (hashlib.sha256 raw bytes) | "
          f"{canon / raw:.2f} | ratio ~1 |")


if __name__ == "__main__":
    main()
