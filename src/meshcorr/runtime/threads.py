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
:func:`parallel_map` and :func:`meshcorr.spectral.basis.prefetch_bases` do: limits
set only inside worker threads were measured to leave BLAS either unlimited
in them or at one thread for the rest of the process.

Ctrl-C: the caller never leaves while a worker still runs, and never waits
with :meth:`threading.Thread.join`. On Python 3.11 a join interrupted by
KeyboardInterrupt releases the running thread's state lock and marks it
stopped (``Thread._wait_for_tstate_lock``, bpo-45274's handler); the
interpreter then finalises under the running worker and crashes (exit 139,
measured with ``concurrent.futures``, whose shutdown joins its workers).
Waits here are on :class:`threading.Event`, and after an interrupt they
run to their end (:func:`wait_for`) before the interrupt is re-raised.
The same holds for scipy's ``cKDTree.query(..., workers=n)``: it runs its
threads as daemons and joins them, so a Ctrl-C there left them querying a
tree the exiting interpreter freed (segmentation faults in
``query_single_point`` during ``Py_FinalizeEx``, 4 of 16 interrupts of a 7k
pair). KD-tree queries go through :func:`kdtree_query` instead.
"""

from __future__ import annotations

import os
import threading
from functools import lru_cache
from typing import Callable, Iterable, TypeVar

import numpy as np
import scipy.linalg  # noqa: F401 - load scipy's own BLAS before the controller scans
import scipy.sparse.linalg  # noqa: F401
from threadpoolctl import ThreadpoolController

from .interrupt import deferred_interrupt

__all__ = ["kdtree_query", "parallel_map", "single_blas_thread", "wait_for"]

#: Fewest KD-tree queries worth a thread of their own: 1000 queries in 5-d take 0.8 ms
#: on one thread and 1.5 ms on all (starting threads costs more than it saves).
QUERIES_PER_THREAD = 5000

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
    :mod:`meshcorr.collection.batch`, which runs one process per core), else the CPU affinity."""
    if os.environ.get("MESHCORR_THREADS", "").strip().isdigit():
        return max(1, int(os.environ["MESHCORR_THREADS"]))
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - not on Linux
        return os.cpu_count() or 1


def wait_for(event: threading.Event) -> None:
    """Wait until ``event`` is set, even through Ctrl-C; then re-raise the interrupt.

    For waits on worker threads after a failure: leaving before they stop
    would let the interpreter exit under them (module docstring).
    """
    interrupted = None
    while True:
        try:
            event.wait()
            break
        except KeyboardInterrupt as exc:  # Ctrl-C, or SIGTERM (runtime.interrupt.Terminated): the first kept
            interrupted = interrupted or exc
    if interrupted is not None:
        raise interrupted


def parallel_map(function: Callable[[T], R], items: Iterable[T]) -> list[R]:
    """``[function(item) for item in items]`` in one thread per core (at most one per item).

    For independent tasks that spend their time in code releasing the GIL
    (LAPACK, SuperLU, KD-tree queries, ``cdist``). BLAS is limited to one
    thread meanwhile, held in the calling thread (module docstring), so the
    tasks do not oversubscribe the cores. The results are those of the
    sequential loop, in order; the first error raised by a task (in item
    order) is re-raised. After an error or Ctrl-C no further item starts,
    and the call returns only once every worker has stopped.
    """
    items = list(items)
    workers = min(len(items), _cores())
    if workers < 2:
        return [function(item) for item in items]
    results: list = [None] * len(items)
    errors: list[BaseException | None] = [None] * len(items)
    queue = iter(range(len(items)))
    lock, stop = threading.Lock(), threading.Event()
    done = [threading.Event() for _ in range(workers)]

    def work(finished: threading.Event) -> None:
        try:
            while not stop.is_set():
                with lock:
                    index = next(queue, None)
                if index is None:
                    return
                try:
                    results[index] = function(items[index])
                except BaseException as error:  # re-raised in the calling thread
                    errors[index] = error
                    stop.set()
        finally:
            finished.set()

    with single_blas_thread():
        started: list[threading.Event] = []
        try:
            for finished in done:
                with deferred_interrupt():  # a started worker is always one waited for
                    threading.Thread(target=work, args=(finished,), name="meshcorr-worker").start()
                    started.append(finished)
            for finished in started:
                finished.wait()
        except BaseException:
            stop.set()
            for finished in started:
                wait_for(finished)
            raise
    for error in errors:
        if error is not None:
            raise error
    return results


def kdtree_query(tree, points: np.ndarray, **options):
    """``tree.query(points, **options)`` of a :class:`scipy.spatial.cKDTree`, over the cores.

    The rows of ``points`` are split into one block per core (blocks of at
    least :data:`QUERIES_PER_THREAD`) and queried by :func:`parallel_map`,
    each with ``workers=1``: the results are those of one query, bit for
    bit, and Ctrl-C cannot leave a query thread running (module docstring).
    Outside the main thread (e.g. inside a :func:`parallel_map` task) the
    query runs in the calling thread.

    Parameters
    ----------
    tree : scipy.spatial.cKDTree
    points : (n, d) float
        Query points.
    **options
        Passed to ``cKDTree.query`` (``k``, ``eps``, ``distance_upper_bound``, ...).

    Returns
    -------
    distances, indices
        As ``cKDTree.query`` returns them.
    """
    points = np.asarray(points)
    blocks = min(_cores(), len(points) // QUERIES_PER_THREAD)
    if blocks < 2 or threading.current_thread() is not threading.main_thread():
        return tree.query(points, workers=1, **options)
    bounds = np.linspace(0, len(points), blocks + 1).astype(int)
    parts = parallel_map(lambda b: tree.query(points[bounds[b]:bounds[b + 1]], workers=1, **options),
                         range(blocks))
    return tuple(np.concatenate([part[i] for part in parts]) for i in range(2))
