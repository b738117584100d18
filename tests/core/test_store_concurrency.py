"""Concurrent writers and runs on one cache: forked processes released together by a barrier.

Every process saves and loads the same keys in the same order (so that most keys are written by several processes
at once); the content of key ``k`` is ``k + arange(n)``, computed here, so every load is checked against an
independent value."""

import multiprocessing
import random

import numpy as np
import pytest
import xarray as xr
from helpers import chain, toy_plugin
from toy_stages import executions

import spflow
from spflow.core import locks
from spflow.core.cache import Store

PROCESSES = 4
KEYS = 80  # 4 processes x 80 keys x (1 save + 1 load) = 640 operations (a quarter for the fallback lock)
FORK = multiprocessing.get_context("fork")


def _key(k: int) -> str:
    return f"{k:064x}"


def _content(k: int) -> np.ndarray:
    return k + np.arange(16, dtype=float)


def _hammer(root, seed, use_flock, keys, barrier, queue):
    locks.USE_FLOCK = use_flock
    rng = random.Random(seed)
    store = Store(root)
    order = list(range(keys))
    for i in range(0, keys - 4, 4):  # the same order everywhere, locally shuffled: writers collide on most keys
        window = order[i:i + 4]
        rng.shuffle(window)
        order[i:i + 4] = window
    errors, operations = [], 0
    barrier.wait()
    for k in order:
        for op in ("save", "load") if rng.random() < 0.5 else ("load", "save"):
            operations += 1
            try:
                if op == "save":
                    ds = xr.Dataset({"y": ("x", _content(k), {"units": "m"})})
                    store.save(_key(k), ds, {"writer": seed}, where=f"key {k}")
                elif store.has(_key(k)):
                    values = store.load(_key(k))["y"].values
                    if not np.array_equal(values, _content(k)):
                        errors.append(f"key {k}: loaded {values[:3]}")
            except Exception as exc:  # noqa: BLE001 - every error counts
                errors.append(f"{op} key {k}: {type(exc).__name__}: {exc}")
    queue.put((operations, errors))


@pytest.mark.parametrize("use_flock, keys", [(True, KEYS), (False, KEYS // 4)], ids=["flock", "o_excl"])
def test_concurrent_saves_and_loads_of_overlapping_keys(tmp_path, use_flock, keys):
    barrier, queue = FORK.Barrier(PROCESSES), FORK.Queue()
    workers = [FORK.Process(target=_hammer, args=(tmp_path, seed, use_flock, keys, barrier, queue))
               for seed in range(PROCESSES)]
    for w in workers:
        w.start()
    reports = [queue.get(timeout=120) for _ in workers]
    for w in workers:
        w.join(timeout=30)
        assert w.exitcode == 0
    assert sum(ops for ops, _ in reports) == PROCESSES * keys * 2 >= (600 if use_flock else 150)
    assert [e for _, errors in reports for e in errors] == []
    store = Store(tmp_path)  # a consistent store: every key once, complete, verified, the right content
    assert sorted(p.name for p in (tmp_path / "objects").glob("*/*")) == sorted(_key(k) for k in range(keys))
    for k in range(keys):
        assert store.verify(_key(k))
        np.testing.assert_array_equal(store.load(_key(k))["y"].values, _content(k))
    assert list((tmp_path / "tmp").iterdir()) == []


def _run_chain(log, cache, barrier, queue):
    try:
        with toy_plugin():
            barrier.wait()
            result = spflow.run(chain(str(log), delay=0.3), cache=cache)
            queue.put((sorted(result.executed), sorted(result.cached),
                       {n: result[n]["y"].values.tolist() for n in result}))
    except BaseException as exc:  # report instead of leaving the parent waiting
        queue.put(exc)
        raise


def test_two_concurrent_runs_compute_each_node_once(log, cache):
    with toy_plugin():
        spflow.status(chain(str(log), delay=0.3), cache=cache)  # plugins imported, keys' parts cached: before fork
    barrier, queue = FORK.Barrier(2), FORK.Queue()
    workers = [FORK.Process(target=_run_chain, args=(log, cache, barrier, queue)) for _ in range(2)]
    for w in workers:
        w.start()
    reports = [queue.get(timeout=120) for _ in workers]
    assert not [r for r in reports if isinstance(r, BaseException)], reports
    (ran1, reused1, values1), (ran2, reused2, values2) = reports
    for w in workers:
        w.join(timeout=30)
        assert w.exitcode == 0
    assert sorted(executions(log)) == sorted(["source:1.0", "scale:2.0", "scale:3.0", "source:5.0", "add"])
    assert sorted(ran1 + ran2) == ["a", "b", "c", "d", "e"]  # each node computed by exactly one of the runs
    assert sorted(ran1 + reused1) == sorted(ran2 + reused2) == ["a", "b", "c", "d", "e"]
    x = np.arange(5.0)
    assert values1 == values2
    np.testing.assert_array_equal(values1["e"], 6 * x + 5 * x)  # (x * 2 * 3) + 5 x, by hand
