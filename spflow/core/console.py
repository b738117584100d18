"""What the ``spflow`` command shows on stderr: the ``spflow`` loggers' records, and the progress of running nodes.

:func:`console_logging` installs a :class:`ConsoleHandler` on the ``spflow`` logger for the duration of a command
(and takes it away after, with the logger's level). Ordinary records at INFO and above are written as ``[spflow] message``. Progress records (those carrying
``record.progress``, from the built-in progress plugin ``spflow/plugins/progress_report.py``): on a terminal, one
status line redrawn in place holding a bar per running node (done/total, elapsed, ETA), cleared before any other line
is written and when the node ends; elsewhere (a file, a pipe, CI) only the milestone records (INFO: about every
10 % or every few seconds) as plain lines. A library user who configures nothing sees none of it.
"""

from __future__ import annotations

import contextlib
import logging
import shutil
import sys
import threading
from collections.abc import Iterator
from typing import Any, TextIO

__all__ = ["ConsoleHandler", "console_logging"]

_BAR = 20  # characters of a bar


def _bar(progress: Any) -> str:
    fraction = progress.fraction
    if fraction is None:
        return f"[{progress.node}] {progress.describe()}"
    filled = int(round(fraction * _BAR))
    return f"[{progress.node}] {'#' * filled}{'.' * (_BAR - filled)} {progress.describe()}"


class ConsoleHandler(logging.Handler):
    """Log lines and node progress on ``stream``; a live status line when ``stream`` is a terminal."""

    def __init__(self, stream: TextIO):
        super().__init__(logging.DEBUG)
        self.stream = stream
        self.live = bool(getattr(stream, "isatty", lambda: False)())
        self.bars: dict[str, Any] = {}
        self.shown = 0  # characters of the status line on screen
        self.guard = threading.Lock()

    def _status(self) -> str:
        width = max(20, shutil.get_terminal_size().columns - 1)
        line = " | ".join(_bar(p) for p in self.bars.values())
        return line if len(line) <= width else line[:width - 3] + "..."

    def _redraw(self, text: str = "") -> None:
        """Clear the status line, write ``text`` (whole lines), draw the status line again."""
        out = ("\r" + " " * self.shown + "\r" if self.shown else "") + text
        status = self._status() if self.live and self.bars else ""
        self.stream.write(out + status)
        self.stream.flush()
        self.shown = len(status)

    def emit(self, record: logging.LogRecord) -> None:
        try:
            progress = getattr(record, "progress", None)
            with self.guard:
                if progress is None:
                    if record.levelno >= logging.INFO:
                        self._redraw(f"[spflow] {record.getMessage()}\n")
                elif progress.finished:
                    if self.bars.pop(progress.node, None) is not None and self.live:
                        self._redraw()
                elif self.live:
                    self.bars[progress.node] = progress
                    self._redraw()
                elif record.levelno >= logging.INFO:
                    self._redraw(f"[spflow] {record.getMessage()}\n")
        except Exception:
            self.handleError(record)


@contextlib.contextmanager
def console_logging(stream: TextIO | None = None) -> Iterator[ConsoleHandler]:
    """Within the block, show the ``spflow`` loggers on ``stream`` (default: the current ``sys.stderr``) as the
    command does; the logger's handlers and level are restored after."""
    logger = logging.getLogger("spflow")
    handler = ConsoleHandler(stream if stream is not None else sys.stderr)
    level = logger.level
    logger.addHandler(handler)
    logger.setLevel(logging.DEBUG if handler.live else logging.INFO)
    try:
        yield handler
    finally:
        logger.removeHandler(handler)
        logger.setLevel(level)
