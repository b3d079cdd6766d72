"""One BLAS thread for small dense products and solves; independent tasks in threads.

Threaded BLAS only adds synchronisation to the small products, solves and
ARPACK iterations of the pipeline (measured 2-10x slower on a loaded
2-core machine), so those stages limit it with :func:`single_blas_thread`.

One :class:`threadpoolctl.ThreadpoolController` is built once and reused:
building one scans the loaded shared libraries (~6 ms each time with
numpy's and scipy's OpenBLAS loaded). The BLAS thread count is
process-wide, and for OpenBLAS's pthreads layer threadpoolctl lets only one
thread change it (the first that does, while it lives); limits set in other
threads are ignored. A stage that runs BLAS in several Python threads must
therefore hold the limit in the calling thread around all of them, as
:func:`parallel_map` and :func:`meshcorr.refine.prefetch_bases` do: limits
set only inside worker threads were measured to leave BLAS either unlimited
in them or at one thread for the rest of the process.
"""

from __future__ import annotations

import os
from concurrent.futures import ThreadPoolExecutor
from functools import lru_cache
from typing import Callable, Iterable, TypeVar

import scipy.linalg  # noqa: F401 - load scipy's own BLAS before the controller scans
import scipy.sparse.linalg  # noqa: F401
from threadpoolctl import ThreadpoolController

__all__ = ["parallel_map", "single_blas_thread"]

T = TypeVar("T")
R = TypeVar("R")


@lru_cache(maxsize=1)
def _controller() -> ThreadpoolController:
    return ThreadpoolController()


def single_blas_thread():
    """Context manager limiting every loaded BLAS library to one thread, restored on exit."""
    return _controller().limit(limits=1, user_api="blas")


def _cores() -> int:
    """Cores this process may use: ``$MESHCORR_THREADS`` if set (e.g. 1 in each worker process of
    :mod:`meshcorr.collection`, which runs one process per core), else the CPU affinity."""
    if os.environ.get("MESHCORR_THREADS", "").strip().isdigit():
        return max(1, int(os.environ["MESHCORR_THREADS"]))
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - not on Linux
        return os.cpu_count() or 1


def parallel_map(function: Callable[[T], R], items: Iterable[T]) -> list[R]:
    """``[function(item) for item in items]`` in one thread per core (at most one per item).

    For independent tasks that spend their time in code releasing the GIL
    (LAPACK, SuperLU, KD-tree queries, ``cdist``). BLAS is limited to one
    thread meanwhile, held in the calling thread (module docstring), so the
    tasks do not oversubscribe the cores. The results are those of the
    sequential loop, in order; the first error raised by a task is re-raised.
    """
    items = list(items)
    workers = min(len(items), _cores())
    if workers < 2:
        return [function(item) for item in items]
    with single_blas_thread(), ThreadPoolExecutor(max_workers=workers) as pool:
        return list(pool.map(function, items))
