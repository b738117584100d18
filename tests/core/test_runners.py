"""Runners behind one interface and the ready queue: a node starts as soon as its inputs exist (not when its whole
topological generation is done), within the worker budget; the lifecycle hooks see every step in order.

Orders are asserted on the events the lifecycle hooks record, never on timings: the slow node of the first test
waits for a file that only the successor of its sibling creates, so a generation-by-generation scheduler cannot pass
it (it would start that successor only after the slow node ended, which never happens: the slow node gives up)."""

import threading

import numpy as np
import pytest
from helpers import chain

import spflow
from spflow.core.runners import BACKENDS, DaskRunner, ProcessRunner, SequentialRunner, ThreadRunner, runner_for


class Timeline:
    """Records every lifecycle event as a tuple, in the order the hooks were called."""

    def __init__(self):
        self.events, self.lock = [], threading.Lock()

    def _add(self, *event):
        with self.lock:
            self.events.append(event)

    @spflow.hookimpl
    def spflow_run_start(self, pipeline, to_run, cached, runner):
        self._add("run_start", pipeline.name, tuple(to_run), tuple(cached), runner)

    @spflow.hookimpl
    def spflow_node_start(self, node, stage, cached):
        self._add("start", node, cached)

    @spflow.hookimpl
    def spflow_node_progress(self, node, done, total, what):
        self._add("progress", node, done, total, what)

    @spflow.hookimpl
    def spflow_node_end(self, node, stage, seconds, cached):
        self._add("end", node, cached)

    @spflow.hookimpl
    def spflow_node_error(self, node, stage, error):
        self._add("error", node, error)

    @spflow.hookimpl
    def spflow_run_end(self, pipeline, result, error):
        self._add("run_end", pipeline.name, tuple(result.executed), error)

    def index(self, *event) -> int:
        return self.events.index(event)


@pytest.fixture
def timeline():
    recorder = Timeline()
    spflow.register_plugin(recorder, name="timeline")
    yield recorder
    spflow.unregister_plugin("timeline")


def _uneven(tmp_path) -> spflow.Pipeline:
    """``slow`` and ``fast`` are independent sources; ``after`` = scale(fast). ``slow`` ends only once ``after``
    has run (it waits for the file ``after`` creates)."""
    signal = str(tmp_path / "after-ran")
    p = spflow.Pipeline("uneven")
    p.add("slow", "toy_source", params={"value": 2.0, "wait_for": signal})
    p.add("fast", "toy_source", params={"value": 3.0})
    p.add("after", "toy_scale", inputs={"data": "fast"}, params={"factor": 4.0, "touch": signal})
    return p


@pytest.mark.parametrize("backend", ["threads", "loky"])
def test_a_slow_node_does_not_hold_back_the_successor_of_its_sibling(toys, cache, tmp_path, timeline, backend):
    result = spflow.run(_uneven(tmp_path), cache=cache, jobs=2, backend=backend)
    assert timeline.index("start", "after", False) < timeline.index("end", "slow", False)
    assert timeline.index("end", "fast", False) < timeline.index("start", "after", False)  # inputs first
    np.testing.assert_array_equal(result["after"]["y"].values, 12.0 * np.arange(5))
    np.testing.assert_array_equal(result["slow"]["y"].values, 2.0 * np.arange(5))


def test_lifecycle_events_of_a_run_and_of_its_cached_rerun(toys, cache, timeline):
    spflow.run(chain(""), cache=cache, backend="sequential")
    events = timeline.events
    assert events[0][:4] == ("run_start", "chain", ("a", "b", "c", "d", "e"), ())  # topological order
    assert isinstance(events[0][4], SequentialRunner)
    assert events[-1] == ("run_end", "chain", ("a", "d", "b", "c", "e"), None)
    # one node at a time: each start is followed by its own end
    assert [e for e in events[1:-1] if e[0] != "progress"] == [
        (kind, n, False) for n in ("a", "d", "b", "c", "e") for kind in ("start", "end")]
    timeline.events.clear()
    spflow.run(chain(""), cache=cache)
    assert timeline.events[0][2:4] == ((), ("a", "b", "c", "d", "e"))
    assert timeline.events[1:-1] == [(kind, n, True) for n in "abcde" for kind in ("start", "end")]
    assert timeline.events[-1] == ("run_end", "chain", (), None)


def test_a_failing_node_reports_the_error_and_the_run_end(toys, cache, timeline):
    p = chain("")
    p.add("bad", "toy_fail", inputs={"data": "a"})
    with pytest.raises(spflow.StageError, match="boom from toy_fail") as caught:
        spflow.run(p, cache=cache)
    errors = [e for e in timeline.events if e[0] == "error"]
    assert [e[1] for e in errors] == ["bad"] and errors[0][2] is caught.value
    assert timeline.events[-1][0] == "run_end" and timeline.events[-1][3] is caught.value


@pytest.mark.parametrize("backend", ["sequential", "threads", "loky"])
def test_stage_progress_reaches_the_hook_in_this_process(toys, cache, timeline, backend):
    p = spflow.Pipeline("steps")
    p.add("count", "toy_steps", params={"n": 7})
    p.add("other", "toy_source")
    spflow.run(p, cache=cache, jobs=2, backend=backend)
    reports = [e[2:] for e in timeline.events if e[0] == "progress"]
    assert reports[0] == (0, 7, "steps") and reports[-1] == (7, 7, "steps")  # first and last always go through
    assert [r[0] for r in reports] == sorted(r[0] for r in reports)
    assert timeline.index("progress", "count", 7, 7, "steps") < timeline.index("end", "count", False)


def test_the_free_budget_is_shared_among_the_nodes_starting_together(toys, cache):
    p = spflow.Pipeline("shares")
    p.add("src", "toy_source")
    p.add("one", "toy_inner", inputs={"data": "src"}, params={"tag": 1})
    p.add("two", "toy_inner", inputs={"data": "src"}, params={"tag": 2})
    result = spflow.run(p, cache=cache, jobs=3, backend="threads")
    assert sorted([result["one"].attrs["n_jobs"], result["two"].attrs["n_jobs"]]) == [1, 2]  # 3 free workers, 2 nodes
    np.testing.assert_array_equal(result["one"]["y"].values, np.arange(5.0) ** 2)
    alone = spflow.run(p.set_params("one", tag=3), cache=cache, jobs=3, backend="threads")
    assert alone.executed == ["one"] and alone["one"].attrs["n_jobs"] == 3


def test_sequential_runner_gives_a_node_the_whole_budget(toys, cache):
    p = spflow.Pipeline("seq")
    p.add("src", "toy_source")
    p.add("one", "toy_inner", inputs={"data": "src"}, params={"tag": 1})
    p.add("two", "toy_inner", inputs={"data": "src"}, params={"tag": 2})
    result = spflow.run(p, cache=cache, jobs=2, backend=SequentialRunner())
    assert result["one"].attrs["n_jobs"] == 2 and result["two"].attrs["n_jobs"] == 2


def test_backend_names_map_to_runner_classes_and_instances_pass_through(toys, cache):
    assert isinstance(runner_for("loky"), ProcessRunner) and isinstance(runner_for("threads"), ThreadRunner)
    assert isinstance(runner_for("sequential"), SequentialRunner)
    assert isinstance(runner_for("dask", "tcp://127.0.0.1:1"), DaskRunner)
    mine = ThreadRunner()
    assert runner_for(mine) is mine
    assert set(BACKENDS) >= {"loky", "threads", "sequential", "dask"}
    result = spflow.run(chain(""), cache=cache, jobs=2, backend=mine)
    np.testing.assert_array_equal(result["e"]["y"].values, 6 * np.arange(5.0) + 5 * np.arange(5.0))


@pytest.mark.parametrize(("backend", "scheduler", "message"), [
    ("gpu", None, r"backend must be a Runner or one of \['dask', 'loky', 'processes', 'sequential', 'threading', "
                  r"'threads'\], got 'gpu'"),
    ("threads", "tcp://127.0.0.1:8786", "--scheduler is for backend 'dask', not 'threads'"),
    (ThreadRunner(), "tcp://127.0.0.1:8786", r"give the scheduler to DaskRunner\(scheduler\)"),
])
def test_bad_backend_arguments_fail_before_any_work(toys, cache, backend, scheduler, message):
    with pytest.raises(spflow.PipelineError, match=message):
        spflow.run(chain(""), cache=cache, jobs=2, backend=backend, scheduler=scheduler)
    assert not cache.exists()
