"""Lock files for concurrent runs: exclusive, released when the holder dies (even by SIGKILL), and the O_EXCL
fallback breaks a sentinel left by a dead process of this host but waits for a live one."""

import multiprocessing
import os
import signal
import socket
import subprocess
import sys

import pytest

from spflow.core import locks
from spflow.core.locks import FileLock

FORK = multiprocessing.get_context("fork")


def _hold_forever(path, use_flock, ready):
    locks.USE_FLOCK = use_flock
    FileLock(path).acquire()
    ready.set()
    signal.pause()


@pytest.mark.parametrize("use_flock", [True, False], ids=["flock", "o_excl"])
def test_a_lock_is_exclusive_and_released_when_its_holder_is_killed(tmp_path, monkeypatch, use_flock):
    monkeypatch.setattr(locks, "USE_FLOCK", use_flock)
    path = tmp_path / "k.lock"
    ready = FORK.Event()
    holder = FORK.Process(target=_hold_forever, args=(path, use_flock, ready))
    holder.start()
    try:
        assert ready.wait(60)
        assert not FileLock(path).acquire(blocking=False)
    finally:
        os.kill(holder.pid, signal.SIGKILL)
        holder.join(30)
    mine = FileLock(path)
    assert mine.acquire(blocking=False)  # the kernel dropped the flock; the dead pid's sentinel was broken
    assert not FileLock(path).acquire(blocking=False)
    mine.release()
    assert FileLock(path).acquire(blocking=False)


def test_a_sentinel_of_a_live_process_or_another_host_is_respected(tmp_path, monkeypatch):
    monkeypatch.setattr(locks, "USE_FLOCK", False)
    sentinel = tmp_path / "k.lock.excl"
    sentinel.write_text(f"{os.getpid()}@{socket.gethostname()}")  # alive: this very process
    assert not FileLock(tmp_path / "k.lock").acquire(blocking=False)
    sentinel.write_text("1@some-other-host")  # cannot tell whether it is alive: wait for it
    assert not FileLock(tmp_path / "k.lock").acquire(blocking=False)
    dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True, text=True)
    sentinel.write_text(f"{dead.stdout.strip()}@{socket.gethostname()}")  # exited: broken
    assert FileLock(tmp_path / "k.lock").acquire(blocking=False)
