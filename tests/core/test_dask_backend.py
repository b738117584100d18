"""A pipeline runs on a Dask distributed cluster started on loopback (processes, TCP)."""

import numpy as np
import pytest
from helpers import chain

import spflow

distributed = pytest.importorskip("distributed")


def test_pipeline_runs_on_local_dask_cluster(toys, cache):
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                                  dashboard_address=None) as cluster:
        assert cluster.scheduler_address.startswith("tcp://127.0.0.1:")
        result = spflow.run(chain(""), cache=cache, jobs=2, backend="dask", scheduler=cluster.scheduler_address)
    assert sorted(result.executed) == ["a", "b", "c", "d", "e"]
    np.testing.assert_array_equal(result["e"]["y"].values, 6 * np.arange(5.0) + 5 * np.arange(5.0))


def test_dask_backend_needs_a_scheduler(toys, cache):
    with pytest.raises(spflow.PipelineError, match="backend 'dask' needs a scheduler address"):
        spflow.run(chain(""), cache=cache, backend="dask", jobs=2)
