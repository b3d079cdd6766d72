"""One BLAS thread for small dense products and solves.

Threaded BLAS only adds synchronisation to the small products, solves and
ARPACK iterations of the pipeline (measured 2-10x slower on a loaded
2-core machine), so those stages limit it with :func:`single_blas_thread`.

One :class:`threadpoolctl.ThreadpoolController` is built once and reused:
building one scans the loaded shared libraries (~6 ms each time with
numpy's and scipy's OpenBLAS loaded). The BLAS thread count is
process-wide, and for OpenBLAS's pthreads layer threadpoolctl lets only one
thread change it (the first that does, while it lives); limits set in other
threads are ignored. A stage that runs BLAS in several Python threads must
therefore hold the limit in the calling thread around all of them (see
:func:`meshcorr.refine.refine_map`): limits set only inside worker threads
were measured to leave BLAS either unlimited in them or at one thread for
the rest of the process.
"""

from __future__ import annotations

from functools import lru_cache

import scipy.linalg  # noqa: F401 - load scipy's own BLAS before the controller scans
import scipy.sparse.linalg  # noqa: F401
from threadpoolctl import ThreadpoolController

__all__ = ["single_blas_thread"]


@lru_cache(maxsize=1)
def _controller() -> ThreadpoolController:
    return ThreadpoolController()


def single_blas_thread():
    """Context manager limiting every loaded BLAS library to one thread, restored on exit."""
    return _controller().limit(limits=1, user_api="blas")
