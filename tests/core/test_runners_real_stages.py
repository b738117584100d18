"""Every runner gives the same results, bit for bit, as running the nodes one by one, on real stages: a forward
ensemble of the simulator and a PCE surrogate fitted to it (few cells, few samples). The Dask runner runs them on a
``distributed.LocalCluster`` (two in-process workers), with their progress relayed back to the hooks here."""

import threading

import pytest
import xarray as xr

import spflow

NODES = ("space", "design", "responses", "proxy")


def _pipeline() -> spflow.Pipeline:
    p = spflow.Pipeline("runners_real")
    p.add("space", "parameter_space", params={"names": ["AD31", "E2WC"], "ranges": {"AD31": [0.0, 2.0],
                                                                                   "E2WC": [1.5, 3.0]}})
    p.add("design", "lhs_design", inputs={"space": "space"}, params={"samples": 8, "seed": 3})
    p.add("responses", "forward", inputs={"design": "design"}, params={"experiments": ["BCF1"], "cells": 12})
    p.add("proxy", "pce", inputs={"space": "space", "design": "design", "responses": "responses"},
          params={"degree_max": 2})
    return p


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    """The nodes run one at a time in this process."""
    result = spflow.run(_pipeline(), cache=tmp_path_factory.mktemp("reference"), backend="sequential")
    return result.keys, {n: result[n].load() for n in NODES}


def _same(result, reference) -> None:
    keys, datasets = reference
    assert result.keys == keys  # provenance keys, hence the cache layout, do not depend on the runner
    for node in NODES:
        xr.testing.assert_identical(result[node], datasets[node])


@pytest.mark.parametrize("backend", ["threads", "loky"])
def test_runners_reproduce_the_sequential_results(tmp_path, reference, backend):
    result = spflow.run(_pipeline(), cache=tmp_path, jobs=2, backend=backend)
    assert sorted(result.executed) == sorted(NODES)
    _same(result, reference)


class Progress:
    def __init__(self):
        self.reports, self.lock = [], threading.Lock()

    @spflow.hookimpl
    def spflow_node_progress(self, node, done, total, what):
        with self.lock:
            self.reports.append((node, done, total, what))


def test_dask_runner_on_a_local_cluster_reproduces_the_sequential_results(tmp_path, reference):
    distributed = pytest.importorskip("distributed")
    progress = Progress()
    spflow.register_plugin(progress, name="progress_probe")
    try:
        with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=False, dashboard_address=None) \
                as cluster, distributed.Client(cluster) as client:
            result = spflow.run(_pipeline(), cache=tmp_path, jobs=2, backend=spflow.DaskRunner(client=client))
    finally:
        spflow.unregister_plugin("progress_probe")
    assert sorted(result.executed) == sorted(NODES)
    _same(result, reference)
    forward = [r for r in progress.reports if r[0] == "responses"]
    assert forward and forward[-1] == ("responses", 8, 8, "samples")  # the last report always reaches the client
