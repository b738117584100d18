"""Caching, partial reruns, staleness explanations, interruption and resumption — observed through execution logs,
keys and store contents."""

import numpy as np
import pytest
from helpers import chain
from toy_stages import Scale, executions

import spflow
from spflow.core.cache import Store


def test_first_run_executes_everything_and_returns_datasets(toys, log, cache):
    result = spflow.run(chain(str(log)), cache=cache)
    assert sorted(result.executed) == ["a", "b", "c", "d", "e"]
    assert result.cached == []
    # e = (arange(5) * 2 * 3) + 5 * arange(5), computed here independently of the stages
    np.testing.assert_array_equal(result["e"]["y"].values, 6 * np.arange(5.0) + 5 * np.arange(5.0))
    assert result["e"]["y"].attrs["units"] == "m"
    assert len(executions(log)) == 5


def test_rerun_with_nothing_changed_executes_nothing(toys, log, cache):
    spflow.run(chain(str(log)), cache=cache)
    before = executions(log)
    result = spflow.run(chain(str(log)), cache=cache)
    assert result.executed == []
    assert sorted(result.cached) == ["a", "b", "c", "d", "e"]
    assert executions(log) == before


def test_param_change_reruns_only_node_and_descendants(toys, log, cache):
    spflow.run(chain(str(log)), cache=cache)
    log.unlink()
    result = spflow.run(chain(str(log), factor=4.0), cache=cache)
    assert sorted(result.executed) == ["b", "c", "e"]
    assert sorted(result.cached) == ["a", "d"]
    assert sorted(executions(log)) == ["add", "scale:3.0", "scale:4.0"]


def test_switching_back_to_earlier_params_is_a_cache_hit(toys, log, cache):
    spflow.run(chain(str(log), factor=2.0), cache=cache)
    spflow.run(chain(str(log), factor=4.0), cache=cache)
    log.unlink()
    result = spflow.run(chain(str(log), factor=2.0), cache=cache)
    assert result.executed == [] and executions(log) == []


def test_status_explains_params_upstream_and_code_causes(toys, log, cache, monkeypatch):
    spflow.run(chain(str(log)), cache=cache)
    assert all(s.fresh for s in spflow.status(chain(str(log)), cache=cache))

    by_node = {s.node: s for s in spflow.status(chain(str(log), factor=4.0), cache=cache)}
    assert by_node["a"].fresh and by_node["d"].fresh
    assert any("params changed: factor: 2.0 -> 4.0" in r for r in by_node["b"].reasons)
    assert by_node["c"].reasons == ["upstream data changed: data (from 'b')"]
    assert by_node["e"].reasons == ["upstream data changed: a (from 'c')"]

    monkeypatch.setattr(Scale, "version", "2")
    by_node = {s.node: s for s in spflow.status(chain(str(log)), cache=cache)}
    assert by_node["b"].reasons[0].startswith("code/version changed: version 1 -> 2")
    assert by_node["a"].fresh  # the source stage did not change


def test_status_of_a_never_run_pipeline(toys, log, cache):
    rows = spflow.status(chain(str(log)), cache=cache)
    assert [r.reasons for r in rows] == [["never run"]] * 5


def test_swapping_a_stage_reruns_that_node_only_downstream(toys, log, cache):
    spflow.run(chain(str(log)), cache=cache)
    swapped = chain(str(log)).set_stage("d", "toy_source", {"value": 7.0, "log": str(log)})
    log.unlink()
    result = spflow.run(swapped, cache=cache)
    assert sorted(result.executed) == ["d", "e"]
    np.testing.assert_array_equal(result["e"]["y"].values, 6 * np.arange(5.0) + 7 * np.arange(5.0))


def test_until_only_and_force(toys, log, cache):
    result = spflow.run(chain(str(log)), cache=cache, until="b")
    assert sorted(result.executed) == ["a", "b"] and sorted(result) == ["a", "b"]
    with pytest.raises(spflow.PipelineError, match="'only' .*not in the cache|not in the cache"):
        spflow.run(chain(str(log)), cache=cache, only="e")
    spflow.run(chain(str(log)), cache=cache)
    log.unlink()
    assert spflow.run(chain(str(log)), cache=cache, only="c").executed == []
    result = spflow.run(chain(str(log)), cache=cache, force="c")
    assert sorted(result.executed) == ["c", "e"]
    assert sorted(executions(log)) == ["add", "scale:3.0"]


def test_exception_keeps_finished_nodes_and_next_run_resumes(toys, log, cache):
    p = chain(str(log))
    p.add("f", "toy_fail", inputs={"data": "e"}, params={"kind": "error", "log": str(log)})
    with pytest.raises(spflow.StageError, match=r"node 'f' \(stage 'toy_fail'\) failed: RuntimeError: boom"):
        spflow.run(p, cache=cache)
    assert sorted(executions(log)) == sorted(["source:1.0", "scale:2.0", "scale:3.0", "source:5.0", "add", "fail"])
    log.unlink()
    p.set_params("f", kind="none")
    result = spflow.run(p, cache=cache)
    assert result.executed == ["f"] and executions(log) == ["fail"]


def test_keyboard_interrupt_keeps_finished_nodes(toys, log, cache):
    p = chain(str(log))
    p.add("f", "toy_fail", inputs={"data": "e"}, params={"kind": "interrupt", "log": str(log)})
    with pytest.raises(KeyboardInterrupt):
        spflow.run(p, cache=cache)
    log.unlink()
    result = spflow.run(chain(str(log)), cache=cache)
    assert result.executed == [] and executions(log) == []


@pytest.mark.parametrize("backend", ["loky", "threads"])
def test_parallel_backends_give_identical_results(toys, log, cache, backend):
    serial = spflow.run(chain(""), cache=cache / "serial")
    parallel = spflow.run(chain(""), cache=cache / backend, jobs=2, backend=backend)
    assert sorted(parallel.executed) == sorted(serial.executed)
    for node in serial:
        assert serial.keys[node] == parallel.keys[node]
        np.testing.assert_array_equal(serial[node]["y"].values, parallel[node]["y"].values)


def test_parallel_failure_still_stores_finished_siblings(toys, log, cache):
    p = spflow.Pipeline("siblings")
    p.add("src", "toy_source", params={"log": str(log)})
    p.add("ok", "toy_scale", inputs={"data": "src"}, params={"log": str(log)})
    p.add("bad", "toy_fail", inputs={"data": "src"}, params={"kind": "error", "log": str(log)})
    with pytest.raises(spflow.StageError, match="'bad'"):
        spflow.run(p, cache=cache, jobs=2)
    p.set_params("bad", kind="none")
    log.unlink()
    result = spflow.run(p, cache=cache, jobs=2)
    assert result.executed == ["bad"]


def test_one_parallel_layer_per_level(toys, cache):
    p = spflow.Pipeline("layers")
    p.add("src", "toy_source", params={"n": 6})
    p.add("lone", "toy_inner", inputs={"data": "src"})
    lone = spflow.run(p, cache=cache, jobs=2)
    assert lone["lone"].attrs["n_jobs"] == 2
    np.testing.assert_array_equal(lone["lone"]["y"].values, np.arange(6.0) ** 2)
    p.add("twin", "toy_inner", inputs={"data": "src"}, params={"tag": 1})
    both = spflow.run(p, cache=cache, jobs=2, force="lone")
    assert sorted(both.executed) == ["lone", "twin"]
    assert both["lone"].attrs["n_jobs"] == 1 and both["twin"].attrs["n_jobs"] == 1


def test_corrupted_entry_is_detected_warned_and_recomputed(toys, log, cache):
    first = spflow.run(chain(str(log)), cache=cache)
    expected = first["c"]["y"].values.copy()
    path = Store(cache)._entry(first.keys["c"]) / "data.nc"
    data = path.read_bytes()
    path.write_bytes(data[: len(data) // 2])  # truncated file
    log.unlink()
    with pytest.warns(spflow.CacheIntegrityWarning, match="node 'c' failed its checksum"):
        result = spflow.run(chain(str(log)), cache=cache)
    assert result.executed == ["c"] and executions(log) == ["scale:3.0"]
    np.testing.assert_array_equal(result["c"]["y"].values, expected)


def test_invalid_output_is_rejected_with_stage_port_variable(toys, cache):
    cases = {
        "units": "stage 'toy_bad_output' port 'output' variable 'y': expected units 'm', found 'ft'",
        "missing": "stage 'toy_bad_output' port 'output' variable 'y': expected a variable",
        "dims": "stage 'toy_bad_output' port 'output': expected dims ['x'], found ['t']",
        "nan": "variable 'y': expected finite values",
        "type": "must return an xarray.Dataset",
    }
    for mode, message in cases.items():
        p = spflow.Pipeline("bad").add("b", "toy_bad_output", params={"mode": mode})
        with pytest.raises(spflow.SpflowError) as info:
            spflow.run(p, cache=cache)
        assert message in str(info.value), (mode, str(info.value))
        assert not Store(cache).has(spflow.status(p, cache=cache)[0].key)


def test_bad_params_and_wiring_fail_before_any_work(toys, log, cache):
    p = chain(str(log)).set_params("c", factor=11.0)
    with pytest.raises(spflow.ParameterError, match=r"stage 'toy_scale' parameter 'factor' = 11.0 is outside .*\[0.0, 10.0\]"):
        spflow.run(p, cache=cache)
    assert executions(log) == []
    p = chain(str(log)).set_params("c", fctor=1.0)
    with pytest.raises(spflow.ParameterError, match="did you mean factor"):
        spflow.run(p, cache=cache)
    p = spflow.Pipeline("w").add("s", "toy_scale")
    with pytest.raises(spflow.PipelineError, match="input port 'data' of stage 'toy_scale' is not wired"):
        spflow.run(p, cache=cache)
    p = spflow.Pipeline("w").add("s", "toy_scale", inputs={"data": "nowhere"})
    with pytest.raises(spflow.PipelineError, match="wired to unknown node 'nowhere'"):
        spflow.run(p, cache=cache)
    p = spflow.Pipeline("w").add("s", "no_such_stage")
    with pytest.raises(spflow.PipelineError, match="unknown stage 'no_such_stage'"):
        spflow.run(p, cache=cache)
    p = spflow.Pipeline("cyc")
    p.add("x", "toy_scale", inputs={"data": "y"}).add("y", "toy_scale", inputs={"data": "x"})
    with pytest.raises(spflow.PipelineError, match="cycle"):
        spflow.run(p, cache=cache)
    assert executions(log) == [] and not (cache / "objects").exists()


def test_add_data_is_content_hashed(toys, cache):
    import xarray as xr

    ds = xr.Dataset({"y": ("x", np.arange(3.0), {"units": "m"})})
    p1 = spflow.Pipeline("d").add_data("obs", ds).add("s", "toy_scale", inputs={"data": "obs"})
    copy = ds.copy(deep=True)
    copy["y"].encoding["source"] = "/somewhere/else.nc"
    p2 = spflow.Pipeline("d").add_data("obs", copy).add("s", "toy_scale", inputs={"data": "obs"})
    r1 = spflow.run(p1, cache=cache)
    r2 = spflow.run(p2, cache=cache)
    assert r1.keys == r2.keys and r2.executed == []
    changed = ds.copy(deep=True)
    changed["y"][0] = 1.0
    r3 = spflow.run(spflow.Pipeline("d").add_data("obs", changed).add("s", "toy_scale", inputs={"data": "obs"}),
                    cache=cache)
    assert sorted(r3.executed) == ["obs", "s"]


@pytest.mark.parametrize("jobs", [True, False, 0, 1.5, "2"])
def test_run_rejects_jobs_that_are_not_a_positive_integer(toys, log, cache, jobs):
    match = r"jobs must be an integer >= 1.*got " + repr(jobs).replace(".", r"\.")
    with pytest.raises(spflow.PipelineError, match=match):
        spflow.run(chain(str(log)), cache=cache, jobs=jobs)
    assert executions(log) == []
