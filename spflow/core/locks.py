"""Inter-process exclusive locks on lock files, for the result store.

``fcntl.flock`` on an open lock file where the platform and file system support it (the kernel releases the lock when
its holder dies, even by ``kill -9``, so a crashed run never leaves a lock behind). Elsewhere (no ``fcntl``, or a
file system answering ``ENOLCK``/``EOPNOTSUPP``, as some network file systems do) a sentinel file created with
``O_CREAT | O_EXCL`` holding ``pid@host``; a sentinel left by a dead process of this host is broken, one from another
host is waited for (remove it by hand if that host crashed: the waiting message names it). Breaking a dead
process's sentinel has a narrow race (two waiters breaking it at once); flock has none, so it is the default.

Lock files are never deleted while the store is in use: deleting a flock'ed file lets a third process lock a fresh
inode while the first still holds the old one (two holders). ``spflow clean`` removes them with the rest of the store.
"""

from __future__ import annotations

import errno
import os
import socket
import sys
import time
from pathlib import Path

try:
    import fcntl
except ImportError:  # pragma: no cover - Windows
    fcntl = None

__all__ = ["FileLock", "USE_FLOCK"]

#: Whether locks use ``flock`` (else the ``O_EXCL`` sentinel); tests switch it off to exercise the fallback.
USE_FLOCK = fcntl is not None

_UNSUPPORTED = {errno.ENOLCK, errno.EOPNOTSUPP, errno.ENOSYS, errno.EINVAL}
_POLL_SECONDS = (0.01, 0.5)  # first and longest wait between attempts at an O_EXCL sentinel


class FileLock:
    """An exclusive lock named by ``path`` (created on demand), held by one process at a time.

    ``acquire(blocking=False)`` returns False at once if another process holds it; ``acquire()`` waits, printing
    ``waiting`` (when given) once to stderr if it has to.
    """

    def __init__(self, path: str | os.PathLike, waiting: str = ""):
        self.path = Path(path)
        self.waiting = waiting
        self._fd: int | None = None
        self._sentinel: Path | None = None

    @property
    def held(self) -> bool:
        return self._fd is not None or self._sentinel is not None

    def acquire(self, blocking: bool = True) -> bool:
        if self.held:
            raise RuntimeError(f"lock {self.path} is already held by this object")
        if USE_FLOCK:
            try:
                return self._acquire_flock(blocking)
            except OSError as exc:
                if exc.errno not in _UNSUPPORTED:
                    raise
        return self._acquire_sentinel(blocking)

    def release(self) -> None:
        if self._fd is not None:
            fd, self._fd = self._fd, None
            os.close(fd)  # closing the descriptor releases the flock
        if self._sentinel is not None:
            sentinel, self._sentinel = self._sentinel, None
            sentinel.unlink(missing_ok=True)

    def __enter__(self) -> FileLock:
        self.acquire()
        return self

    def __exit__(self, *exc) -> None:
        self.release()

    # -- flock ---------------------------------------------------------------------------------------------------
    def _acquire_flock(self, blocking: bool) -> bool:
        fd = os.open(self.path, os.O_RDWR | os.O_CREAT, 0o644)
        try:
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except BlockingIOError:
                if not blocking:
                    os.close(fd)
                    return False
                self._say_waiting(f"lock file {self.path}")
                fcntl.flock(fd, fcntl.LOCK_EX)
        except BaseException:
            os.close(fd)
            raise
        self._fd = fd
        return True

    # -- O_EXCL sentinel -----------------------------------------------------------------------------------------
    def _acquire_sentinel(self, blocking: bool) -> bool:
        sentinel = self.path.with_name(self.path.name + ".excl")
        owner = f"{os.getpid()}@{socket.gethostname()}"
        pause, said = _POLL_SECONDS[0], False
        while True:
            try:
                fd = os.open(sentinel, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o644)
            except FileExistsError:
                if _dead_local_owner(sentinel):
                    sentinel.unlink(missing_ok=True)  # left by a crashed process of this host
                    continue
                if not blocking:
                    return False
                if not said:
                    self._say_waiting(f"lock file {sentinel} (held by {_owner(sentinel) or 'an unknown process'})")
                    said = True
                time.sleep(pause)
                pause = min(2 * pause, _POLL_SECONDS[1])
                continue
            with os.fdopen(fd, "w") as fh:
                fh.write(owner)
            self._sentinel = sentinel
            return True

    def _say_waiting(self, what: str) -> None:
        if self.waiting:
            print(f"[spflow] {self.waiting}; waiting for {what}", file=sys.stderr, flush=True)


def _owner(sentinel: Path) -> str:
    try:
        return sentinel.read_text().strip()
    except OSError:
        return ""


def _dead_local_owner(sentinel: Path) -> bool:
    pid, _, host = _owner(sentinel).partition("@")
    if host != socket.gethostname() or not pid.isdigit():
        return False  # another host's process, or being written right now: wait
    try:
        os.kill(int(pid), 0)
    except ProcessLookupError:
        return True
    except PermissionError:  # alive, owned by another user
        return False
    return False
