"""Executor overhead, scheduling and canonical-hashing throughput (a benchmark, not a test).

1. A 50-node DAG of trivial stages, all cache hits: wall time of ``spflow.run`` (target < 1 s). Baseline in the same
   run: the time to load the same 50 results with plain ``xarray.open_dataset`` (the unavoidable I/O).
2. Canonical hashing of a ~100 MB Dataset: MB/s of ``canonical_hash`` vs ``hashlib.sha256`` over the raw bytes.
3. Scheduling of a DAG with uneven node times (stages that burn CPU: one long source next to a chain of four short
   nodes) on 2 workers (loky processes): wall time, CPU time (this process, its live descendants -- the loky workers
   -- and its reaped children, from /proc and getrusage: Linux) and core utilisation CPU / (wall x cores), for
   * the ready queue (``spflow.run(jobs=2)``),
   * generation-by-generation scheduling, the executor's former rule, replayed with the public API: one
     ``spflow.run(only=generation, jobs=2)`` per topological generation, each waiting for the whole previous one,
   * ``jobs=1`` (one node at a time), and the ideal bound max(critical path, total CPU / 2).

Run: ``python benchmarks/bench_executor.py [--scale S] [--sleep] [--scheduling-only]`` (S multiplies the node times;
1 = 4 s long node; ``--sleep``: the nodes sleep instead of burning CPU, which measures the scheduling alone, immune to
other load on a shared machine -- the CPU columns then only show the executor's own overhead).
"""

from __future__ import annotations

import argparse
import hashlib
import os
import resource
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


class Burn(spflow.Stage):
    """Burns ``seconds`` of CPU (a pure-Python loop: holds the GIL, as most stage code does), or sleeps them."""

    name = "bench_burn"
    inputs = {"after": None}
    optional_inputs = frozenset({"after"})
    params = {"seconds": spflow.Param(float, 1.0, bounds=(0.0, 600.0), unit="s"), "tag": spflow.Param(str, ""),
              "sleep": spflow.Param(bool, False)}

    def run(self, ctx, after=None):
        if self.params["sleep"]:
            time.sleep(self.params["seconds"])
            return xr.Dataset({"burnt": ((), 0.0, {"units": "s"})})
        t0 = time.process_time()
        while time.process_time() - t0 < self.params["seconds"]:
            sum(range(1000))
        return xr.Dataset({"burnt": ((), time.process_time() - t0, {"units": "s"})})


@spflow.hookimpl
def spflow_register_stages(register):
    register(Burn)


def _uneven(scale: float, tag: str, sleep: bool = False) -> tuple[spflow.Pipeline, dict[str, float]]:
    """``long`` (4 units) beside the chain s1 -> s2 -> s3 -> s4 (1 unit each)."""
    p = spflow.Pipeline("uneven")
    times = {"long": 4.0 * scale, "s1": scale, "s2": scale, "s3": scale, "s4": scale}
    common = {"tag": tag, "sleep": sleep}
    p.add("long", "bench_burn", params={"seconds": times["long"], **common})
    p.add("s1", "bench_burn", params={"seconds": times["s1"], **common})
    for k in (2, 3, 4):
        p.add(f"s{k}", "bench_burn", inputs={"after": f"s{k - 1}"}, params={"seconds": times[f"s{k}"], **common})
    return p, times


def _cpu_seconds() -> float:
    """CPU seconds of this process, its live descendants and its reaped children."""
    tick = os.sysconf("SC_CLK_TCK")
    stats = {}
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                fields = (entry / "stat").read_text().rsplit(")", 1)[1].split()
            except OSError:
                continue
            stats[int(entry.name)] = (int(fields[1]), (int(fields[11]) + int(fields[12])) / tick)
    mine, total, grew = {os.getpid()}, 0.0, True
    while grew:
        grew = False
        for pid, (ppid, _) in stats.items():
            if ppid in mine and pid not in mine:
                mine.add(pid)
                grew = True
    total = sum(stats[pid][1] for pid in mine if pid in stats)
    children = resource.getrusage(resource.RUSAGE_CHILDREN)
    return total + children.ru_utime + children.ru_stime


def _measure(run) -> tuple[float, float]:
    cpu0, t0 = _cpu_seconds(), time.perf_counter()
    run()
    return time.perf_counter() - t0, _cpu_seconds() - cpu0


def bench_scheduling(scale: float, sleep: bool) -> list[tuple[str, float, float]]:
    """(label, wall s, CPU s) of each way of running the uneven DAG, each on a fresh cache."""
    spflow.register_plugin(sys.modules[__name__], name="bench_burn")
    rows = []
    try:
        with tempfile.TemporaryDirectory() as tmp:
            warm, _ = _uneven(0.01, "warm-up")
            spflow.run(warm, cache=Path(tmp, "warm"), jobs=2)  # start the loky workers outside the measurements

            def ready():
                spflow.run(_uneven(scale, "ready", sleep)[0], cache=Path(tmp, "ready"), jobs=2)

            def generations():
                import networkx as nx

                pipe = _uneven(scale, "generations", sleep)[0]
                for generation in nx.topological_generations(pipe.graph()):
                    spflow.run(pipe, cache=Path(tmp, "generations"), jobs=2, only=sorted(generation))

            def one_at_a_time():
                spflow.run(_uneven(scale, "jobs1", sleep)[0], cache=Path(tmp, "jobs1"), jobs=1)

            for label, how in (("ready queue, jobs=2", ready), ("generations, jobs=2 (former rule)", generations),
                               ("one node at a time, jobs=1", one_at_a_time)):
                rows.append((label, *_measure(how)))
    finally:
        spflow.unregister_plugin("bench_burn")
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scale", type=float, default=1.0, help="multiplies the node times (1: 4 s long node)")
    parser.add_argument("--sleep", action="store_true", help="nodes sleep instead of burning CPU: the scheduling "
                                                             "alone, immune to other load on the machine")
    parser.add_argument("--scheduling-only", action="store_true", help="skip the cache-hit and hashing benchmarks")
    args = parser.parse_args()
    cores = os.cpu_count() or 1
    _, times = _uneven(args.scale, "")
    bound = max(times["long"], times["s1"] + times["s2"] + times["s3"] + times["s4"], sum(times.values()) / 2)
    print(f"uneven DAG (long {times['long']:g} s | s1->s2->s3->s4 {times['s1']:g} s each) on {cores} core(s); "
          f"ideal wall with 2 workers: {bound:.2f} s")
    print("| scheduling | wall (s) | CPU (s) | core utilisation CPU/(wall x cores) | wall / ideal |")
    print("|---|---|---|---|---|")
    for label, wall, cpu in bench_scheduling(args.scale, args.sleep):
        print(f"| {label} | {wall:.2f} | {cpu:.2f} | {cpu / (wall * cores):.0%} | {wall / bound:.2f} |")
    if args.scheduling_only:
        return
    hits, base = bench_cache_hits()
    canon, raw = bench_hashing()
    print("| benchmark | spflow | baseline | ratio (spflow/baseline) | target |")
    print("|---|---|---|---|---|")
    print(f"| 50-node DAG, all cache hits (s) | {hits:.3f} | {base:.3f} (bare netCDF loads) | {hits / base:.2f} | < 1 s |")
    print(f"| canonical hash of 100 MB Dataset (MB/s) | {canon:.0f} | {raw:.0f} (hashlib.sha256 raw bytes) | "
          f"{canon / raw:.2f} | ratio ~1 |")


if __name__ == "__main__":
    main()
