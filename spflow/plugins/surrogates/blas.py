"""One-thread BLAS for small dense factorisations and products (PCE regression fits, hybrid LARS refits, blockwise
PCE evaluation).

Multi-threaded BLAS on matrices of a few hundred rows spends more time synchronising than computing, and on a
machine whose cores are already busy (joblib workers, other jobs) it becomes many times slower than one thread.
Parallelism belongs one level up (over outputs, samples or pipeline nodes). The controller scans the loaded BLAS
libraries once; entering the limit then costs microseconds.
"""

from __future__ import annotations

from contextlib import AbstractContextManager
from functools import cache

from threadpoolctl import ThreadpoolController

__all__ = ["single_threaded_blas"]


@cache
def _controller() -> ThreadpoolController:
    return ThreadpoolController()


def single_threaded_blas() -> AbstractContextManager:
    """Context manager limiting every loaded BLAS library to one thread."""
    return _controller().limit(limits=1, user_api="blas")
