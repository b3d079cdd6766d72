"""The Dask cluster of a batch: a local one started here, or an existing scheduler.

:func:`local_client` starts a ``dask.distributed.LocalCluster`` of one
single-threaded worker process per core whose workers ignore Ctrl-C (this
process stops them); :func:`connect` reaches a scheduler that runs elsewhere.
Dask is the optional extra ``meshcorr[dask]``: :func:`import_distributed`
names it when it is missing.
"""

from __future__ import annotations

import logging
import os
import signal
import threading
from contextlib import contextmanager

from ..errors import ParameterError
from ..runtime.messages import one_line

__all__ = ["CONNECT_TIMEOUT", "DASK_MISSING", "MAX_WORKERS", "WORKERS_PER_CORE", "connect", "import_distributed",
           "local_client", "max_workers"]

#: The most local worker processes a batch may start: this many per core, and never more than
#: :data:`MAX_WORKERS` (each process holds its meshes and matrices; more only queue for the cores).
WORKERS_PER_CORE = 4
MAX_WORKERS = 256


def max_workers() -> int:
    """The most local workers on this machine: :data:`WORKERS_PER_CORE` per core, at most :data:`MAX_WORKERS`."""
    return min(WORKERS_PER_CORE * (os.cpu_count() or 1), MAX_WORKERS)

#: Seconds :func:`connect` waits for a scheduler to answer.
CONNECT_TIMEOUT = 30
DASK_MISSING = ("meshcorr batch runs on Dask, which is not installed: pip install \"meshcorr[dask]\" "
                "(or pip install \"dask[distributed]\").")


def import_distributed():
    """The ``distributed`` package (Dask's scheduler and workers).

    Raises
    ------
    ParameterError
        It is not installed (:data:`DASK_MISSING`).
    """
    try:
        import distributed
    except ImportError:
        raise ParameterError(DASK_MISSING) from None
    return distributed


@contextmanager
def local_client(distributed, n_workers: int | None):
    """A client of a local cluster of single-threaded worker processes, started here and stopped at the end.

    ``n_workers`` processes (default: one per core), each with one thread for
    BLAS, OpenMP and the pipeline's own pools.
    """
    workers = n_workers or os.cpu_count() or 1
    # One process per core, so one thread each: for BLAS, and for the pipeline's own thread pools
    # (meshcorr.runtime.threads; the maps are those of the threaded runs).
    env = {name: "1" for name in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS",
                                  "MESHCORR_THREADS")}
    # silence_logs: Dask's own warnings and errors (the tasks cancelled by Ctrl-C, a worker's heartbeat to
    # the scheduler that an interrupt stopped first) are not the user's business; a pair's failure comes
    # back through its future and is recorded.
    # dashboard_address ":0": the scheduler's HTTP server on a free port (None still asked for 8787 and
    # warned "Port 8787 is already in use" beside another Dask cluster).
    with workers_ignore_ctrl_c():
        cluster = distributed.LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                                           host="127.0.0.1", dashboard_address=":0", env=env,
                                           silence_logs=logging.CRITICAL)
    with cluster, distributed.Client(cluster) as local:
        yield local


@contextmanager
def workers_ignore_ctrl_c():
    """SIGINT ignored while the local cluster starts its worker processes, which inherit that.

    Ctrl-C in a terminal goes to the whole process group: the workers got it too and each printed
    a traceback before this process could stop them. Ignored signals (not handlers) survive the
    workers' spawn; this process restores its own handler at once and stops the workers itself.
    An interrupt while the cluster starts is lost (press Ctrl-C again). Outside the main thread
    (where signals cannot be set) the cluster starts as it is.
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)


def connect(address: str):
    """A ``distributed.Client`` of the scheduler at ``address`` (e.g. ``tcp://10.0.0.5:8786``).

    Raises
    ------
    ParameterError
        Dask is missing, or no scheduler answers at ``address`` within :data:`CONNECT_TIMEOUT` seconds.
    """
    distributed = import_distributed()
    try:
        return distributed.Client(address, timeout=CONNECT_TIMEOUT)
    except (OSError, TimeoutError, ValueError) as exc:
        raise ParameterError(f"No Dask scheduler answered at {address} ({one_line(exc)}): start one with "
                             "'dask scheduler' and workers with 'dask worker ADDRESS', or omit --scheduler "
                             "to use a local cluster.") from None
