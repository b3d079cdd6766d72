"""Ctrl-C and SIGTERM for one command-line run: the first stops the work, later ones wait for the cleanup."""

from __future__ import annotations

import signal
import threading
from contextlib import ExitStack, contextmanager

from ..runtime.interrupt import Terminated

#: The signals a run stops on as on Ctrl-C: SIGINT raises KeyboardInterrupt, SIGTERM (``kill``, a
#: scheduler's time limit) :class:`~meshcorr.runtime.interrupt.Terminated`, a KeyboardInterrupt too.
STOP_SIGNALS = {signal.SIGINT: KeyboardInterrupt, signal.SIGTERM: Terminated}


@contextmanager
def interrupt_once(*, ignore_after: bool = False):
    """SIGINT and SIGTERM raise KeyboardInterrupt (:class:`Terminated` for SIGTERM) the first time, and are
    ignored after that.

    The cleanup an interrupt starts (waiting for worker threads, removing
    temporary files) then cannot itself be interrupted; a second Ctrl-C (or
    SIGTERM) meanwhile does nothing. ``ignore_after=True`` leaves both
    ignored when the block ends instead of restoring the previous handlers:
    for a run that owns the process, so that a signal while the interpreter
    exits (after the outputs are written) cannot turn a finished run into a
    traceback. Outside the main thread, the block runs with the handlers as
    they are; a signal that is ignored on entry (SIGINT of a job started in
    the background by a shell without job control, or under ``nohup``: the
    process was asked not to stop on it) stays ignored.
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    interrupted = False

    def handler(signum, frame):
        nonlocal interrupted
        if not interrupted:
            interrupted = True
            raise STOP_SIGNALS[signum]

    with ExitStack() as stack:
        for signum in STOP_SIGNALS:
            if signal.getsignal(signum) is not signal.SIG_IGN:
                previous = signal.signal(signum, handler)
                stack.callback(signal.signal, signum, signal.SIG_IGN if ignore_after else previous)
        yield
