"""Ctrl-C for one command-line run: the first interrupt stops the work, later ones wait for the cleanup."""

from __future__ import annotations

import signal
import threading
from contextlib import contextmanager


@contextmanager
def interrupt_once(*, ignore_after: bool = False):
    """SIGINT raises KeyboardInterrupt the first time, and is ignored after that.

    The cleanup an interrupt starts (waiting for worker threads, removing
    temporary files) then cannot itself be interrupted; a second Ctrl-C
    meanwhile does nothing. ``ignore_after=True`` leaves SIGINT ignored when
    the block ends instead of restoring the previous handler: for a run that
    owns the process, so that a Ctrl-C while the interpreter exits (after the
    outputs are written) cannot turn a finished run into a traceback.
    Outside the main thread, and where SIGINT is ignored (a job started in
    the background by a shell without job control, or under ``nohup``: the
    process was asked not to stop on Ctrl-C), the block runs with the
    handler as it is.
    """
    if (threading.current_thread() is not threading.main_thread()
            or signal.getsignal(signal.SIGINT) is signal.SIG_IGN):
        yield
        return
    interrupted = False

    def handler(signum, frame):
        nonlocal interrupted
        if not interrupted:
            interrupted = True
            raise KeyboardInterrupt

    previous = signal.signal(signal.SIGINT, handler)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, signal.SIG_IGN if ignore_after else previous)
