"""Composing pipelines: ``Pipeline.include`` copies a sub-pipeline under a prefix, sharing named nodes; nodes with
the same provenance key are computed once per run and a sub-pipeline's cache is reused by the composed one."""

import numpy as np
import pytest
from helpers import chain
from toy_stages import executions

import spflow


def test_included_nodes_are_prefixed_and_rewired(toys, log):
    whole = spflow.Pipeline("whole")
    whole.include(chain(str(log)), "left")
    assert sorted(whole.nodes) == ["left.a", "left.b", "left.c", "left.d", "left.e"]
    assert whole.nodes["left.e"].inputs == {"a": "left.c", "b": "left.d"}
    assert whole.nodes["left.b"].params == {"factor": 2.0, "log": str(log)}


def test_shared_node_feeds_every_included_copy(toys, log, cache):
    whole = spflow.Pipeline("whole")
    whole.add("a", "toy_source", params={"value": 2.0, "log": str(log)})
    whole.include(chain(str(log), factor=1.0), "one", share=["a"])
    whole.include(chain(str(log), factor=4.0), "two", share=["a"])
    assert whole.nodes["one.b"].inputs == {"data": "a"}
    result = spflow.run(whole, cache=cache)
    # e = a * factor * 3 + 5 * arange(5) with a = 2 * arange(5): computed here from the toy stages' definitions
    x = np.arange(5.0)
    np.testing.assert_array_equal(result["one.e"]["y"].values, 2 * x * 1.0 * 3 + 5 * x)
    np.testing.assert_array_equal(result["two.e"]["y"].values, 2 * x * 4.0 * 3 + 5 * x)


def test_identical_nodes_run_once_and_reuse_the_sub_pipelines_cache(toys, log, cache):
    spflow.run(chain(str(log)), cache=cache)
    log.unlink()
    whole = spflow.Pipeline("whole")
    whole.include(chain(str(log)), "one")
    whole.include(chain(str(log), factor=4.0), "two")
    result = spflow.run(whole, cache=cache)
    # "one" is the chain run above (all cached); in "two" only b, c, e differ, and d equals one.d (cached)
    assert sorted(result.executed) == ["two.b", "two.c", "two.e"]
    assert sorted(executions(log)) == ["add", "scale:3.0", "scale:4.0"]


def test_twins_in_one_run_compute_once(toys, log, cache):
    whole = spflow.Pipeline("whole")
    whole.include(chain(str(log)), "one")
    whole.include(chain(str(log)), "two")
    result = spflow.run(whole, cache=cache, jobs=2)
    assert len(result.executed) == 5 and sorted(result.cached) == [f"two.{n}" for n in "abcde"]
    assert sorted(executions(log)) == sorted(["source:1.0", "source:5.0", "scale:2.0", "scale:3.0", "add"])
    np.testing.assert_array_equal(result["two.e"]["y"].values, result["one.e"]["y"].values)


def test_include_rejects_clashes_and_unknown_shared_nodes(toys, log):
    whole = spflow.Pipeline("whole")
    whole.include(chain(str(log)), "one")
    with pytest.raises(spflow.PipelineError, match="already has a node 'one.a'"):
        whole.include(chain(str(log)), "one")
    with pytest.raises(spflow.PipelineError, match="no node 'zz'"):
        whole.include(chain(str(log)), "three", share=["zz"])


def test_scoped_result_serves_an_included_pipeline_under_its_own_names(toys, log, cache):
    whole = spflow.Pipeline("whole")
    whole.add("a", "toy_source", params={"value": 2.0, "log": str(log)})
    whole.include(chain(str(log), factor=4.0), "two", share=["a"])
    result = spflow.run(whole, cache=cache)
    two = result.scoped("two")
    assert sorted(two) == ["a", "b", "c", "d", "e"]
    np.testing.assert_array_equal(two["e"]["y"].values, result["two.e"]["y"].values)
    assert sorted(two.executed) == ["a", "b", "c", "d", "e"] and two.cached == []
