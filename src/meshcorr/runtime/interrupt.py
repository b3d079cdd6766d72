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
arrives inside such a block and delivers it when the block ends.
"""

from __future__ import annotations

import signal
import threading
from contextlib import contextmanager

__all__ = ["deferred_interrupt"]


@contextmanager
def deferred_interrupt():
    """Hold SIGINT while the block runs; pass it to the SIGINT handler once the block has ended.

    Only in the main thread (the one Python delivers signals to) and only
    while a Python-level handler is installed (the default one, which raises
    KeyboardInterrupt, or the CLI's); elsewhere the block runs as it is.
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = signal.getsignal(signal.SIGINT)
    if not callable(previous):  # SIG_IGN, SIG_DFL or a handler not installed from Python
        yield
        return
    received: list = []
    signal.signal(signal.SIGINT, lambda signum, frame: received.append(frame))
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)
        if received:
            previous(signal.SIGINT, received[0])
