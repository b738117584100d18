"""One-thread BLAS for small dense factorisations and products (PCE regression fits, hybrid LARS refits, blockwise
PCE evaluation).

Multi-threaded BLAS on matrices of a few hundred rows spends more time synchronising than computing, and on a
machine whose cores are already busy (joblib workers, other jobs) it becomes many times slower than one thread.
Parallelism belongs one level up (over outputs, samples or pipeline nodes). The controller scans the loaded BLAS
libraries once; entering the limit then costs microseconds.
"""

from __future__ import annotations

from contextlib import AbstractContextManager, nullcontext
from functools import cache

from threadpoolctl import ThreadpoolController

__all__ = ["single_threaded_blas", "SERIAL_PRODUCT_SIZE"]

#: OpenBLAS runs a GEMM with m n k below 65536 x GEMM_MULTITHREAD_THRESHOLD (4) on one thread by itself; for such
#: products the limit is pure overhead (~25 us per entry, e.g. one MCMC step's single-point prediction).
SERIAL_PRODUCT_SIZE = 65536 * 4


@cache
def _controller() -> ThreadpoolController:
    return ThreadpoolController()


def single_threaded_blas(product_size: int | None = None) -> AbstractContextManager:
    """Context manager limiting every loaded BLAS library to one thread; a no-op when the work is a product of
    ``product_size = m n k`` multiply-adds small enough that BLAS keeps it on one thread anyway."""
    if product_size is not None and product_size < SERIAL_PRODUCT_SIZE:
        return nullcontext()
    return _controller().limit(limits=1, user_api="blas")
