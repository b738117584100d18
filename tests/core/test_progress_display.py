"""Progress as the user sees it: the built-in progress plugin's records (milestones about every 10 %, elapsed time
and a linear ETA) and the ``spflow`` command's console (a live line on a terminal, plain lines elsewhere); the run's
log through the standard ``logging`` module, silent unless configured."""

import io
import logging
import re

import pytest
from helpers import chain

import spflow
from spflow.core.console import console_logging
from spflow.plugins import progress_report


class Terminal(io.StringIO):
    def isatty(self):
        return True


def test_milestones_every_tenth_and_an_eta_at_the_rate_since_the_first_report(monkeypatch, caplog):
    clock = iter(range(0, 1000))  # each call to time.monotonic advances one second
    monkeypatch.setattr(progress_report.time, "monotonic", lambda: float(next(clock)))
    progress_report.spflow_node_start(node="n", stage=None, cached=False)  # t = 0
    with caplog.at_level(logging.DEBUG, logger="spflow.stage.n"):
        for done in range(0, 41):  # t = 1 .. 41: fast reports, 40 steps of 1 s each
            progress_report.spflow_node_progress(node="n", done=done, total=40, what="steps")
    info = [r.progress for r in caplog.records if r.levelno == logging.INFO]
    # first report, then every 4 steps (10 % of 40) -- or 5 s, which 4 steps of 1 s never reach
    assert [p.done for p in info] == list(range(0, 41, 4))
    assert len([r for r in caplog.records if r.levelno == logging.DEBUG]) == 41 - len(info)
    tenth = info[1]  # done 4 at t = 5: 5 s since the start; 4 steps in the 4 s since the first report, 36 left
    assert tenth.elapsed == 5.0 and tenth.eta == pytest.approx(36 * 4 / 4)
    assert tenth.describe() == "4/40 steps (10 %), 0:05 elapsed, ETA 0:36"
    assert info[-1].describe() == "40/40 steps (100 %), 0:41 elapsed"


def test_a_slow_stage_gets_a_line_every_five_seconds(monkeypatch, caplog):
    clock = iter(range(0, 1000, 3))  # 3 s per call
    monkeypatch.setattr(progress_report.time, "monotonic", lambda: float(next(clock)))
    progress_report.spflow_node_start(node="m", stage=None, cached=False)
    with caplog.at_level(logging.INFO, logger="spflow.stage.m"):
        for done in range(0, 6):  # 1 % each, every 3 s
            progress_report.spflow_node_progress(node="m", done=done, total=100, what="samples")
    assert [r.progress.done for r in caplog.records] == [0, 2, 4]  # at 3 s, then at 9 and 15 s (>= 5 s apart)


def test_plain_lines_off_a_terminal(toys, cache):
    stream = io.StringIO()
    p = spflow.Pipeline("steps")
    p.add("count", "toy_steps", params={"n": 30})
    with console_logging(stream):
        spflow.run(p, cache=cache)
    lines = stream.getvalue().splitlines()
    assert "\r" not in stream.getvalue()
    assert lines[0] == "[spflow] steps: 1 node(s) to run, 0 cached"
    assert lines[1] == "[spflow] count: running toy_steps ..."
    progress = [line for line in lines if "steps (" in line]
    assert progress[0].startswith("[spflow] count: 0/30 steps (0 %), 0:00 elapsed")
    assert progress[-1].startswith("[spflow] count: 30/30 steps (100 %)") and len(progress) <= 11
    assert lines[-1].startswith("[spflow] (1/1) count: ran toy_steps in ")


def test_a_live_line_on_a_terminal(toys, cache):
    stream = Terminal()
    p = spflow.Pipeline("steps")
    p.add("count", "toy_steps", params={"n": 4})
    with console_logging(stream) as handler:
        spflow.run(p, cache=cache)
    assert handler.live and handler not in logging.getLogger("spflow").handlers  # taken away after the block
    text = stream.getvalue()
    bars = re.findall(r"\[count\] [#.]{20} [^\r\n]*", text)
    assert bars[0].startswith("[count] .................... 0/4 steps (0 %), 0:00 elapsed")
    assert bars[-1].startswith("[count] #################### 4/4 steps (100 %)")
    last = text.rsplit("\r", 1)[-1]  # the bar was cleared before the closing log line
    assert text.endswith("\n") and "[spflow] (1/1) count: ran toy_steps in " in last.splitlines()[-1]
    assert "[spflow] count: 0/4" not in text and "[spflow] count: 4/4" not in text  # no plain progress lines


def test_the_library_logs_through_logging_and_prints_nothing(toys, cache, capfd, caplog):
    with caplog.at_level(logging.INFO, logger="spflow"):
        spflow.run(chain(""), cache=cache, jobs=2, backend="threads")
    captured = capfd.readouterr()
    assert captured.out == "" and captured.err == ""
    names = {r.name for r in caplog.records}
    assert {"spflow.executor", "spflow.stage.a", "spflow.stage.e"} <= names
    ends = sorted(r.getMessage().split(") ", 1)[1].split(":")[0] for r in caplog.records if "ran toy_" in r.message)
    assert ends == ["a", "b", "c", "d", "e"]
