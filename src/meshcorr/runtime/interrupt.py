"""Ctrl-C (SIGINT) held back where a KeyboardInterrupt would do harm.

Python raises KeyboardInterrupt in the main thread at whatever bytecode runs
when SIGINT arrives. Two places cannot take it: code that catches
``BaseException`` (trimesh's guards around its optional imports turn a
Ctrl-C during ``import trimesh`` into a half-imported module, and the run
then fails later with an unrelated ``TypeError``; its parsers try a fast
path and fall back on any exception, so a Ctrl-C while a file is parsed
was lost: both measured, :mod:`meshcorr.io` holds SIGINT around them), and the few bytecodes
between starting a worker thread and recording it, after which nothing
would wait for the worker before the interpreter exits
(:mod:`meshcorr.runtime.threads`). :func:`deferred_interrupt` holds a SIGINT that
arrives inside such a block and delivers it when the block ends (and SIGTERM,
which the command line turns into :class:`Terminated`, likewise).
"""

from __future__ import annotations

import signal
import threading
from contextlib import contextmanager

__all__ = ["Terminated", "deferred_interrupt"]

#: The signals held back: Ctrl-C, and SIGTERM where the command line stops on it as on Ctrl-C.
HELD_SIGNALS = (signal.SIGINT, signal.SIGTERM)


class Terminated(KeyboardInterrupt):
    """SIGTERM (``kill PID``, a job scheduler's time limit) in a run that stops on it as on Ctrl-C.

    A KeyboardInterrupt, so that every cleanup of an interrupted run (temporary files removed, worker
    threads waited for, a batch's summary written) runs for it too; the command line exits 143 for it.
    """


@contextmanager
def deferred_interrupt():
    """Hold SIGINT (and SIGTERM) while the block runs; pass it to its handler once the block has ended.

    Only in the main thread (the one Python delivers signals to) and only
    for a signal whose handler was installed from Python (for SIGINT the
    default one, which raises KeyboardInterrupt, or the CLI's; for SIGTERM
    the CLI's); elsewhere the block runs as it is.
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = {signum: signal.getsignal(signum) for signum in HELD_SIGNALS}
    held = [signum for signum, handler in previous.items() if callable(handler)]
    received: list = []
    for signum in held:
        signal.signal(signum, lambda number, frame: received.append((number, frame)))
    try:
        yield
    finally:
        for signum in held:
            signal.signal(signum, previous[signum])
        if received:
            number, frame = received[0]
            previous[number](number, frame)
