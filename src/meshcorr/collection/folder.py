"""The output folder of a batch: one run at a time writes into it.

Two batches into one folder each rewrite ``summary.json`` and ``summary.csv``
from their own records: the last one to write wins, and the records of the
other are lost although both end well. :func:`output_lock` holds an
exclusive, non-blocking lock (``flock``) on ``OUT/.lock`` for the whole run
and refuses a second run while the first holds it. The lock goes with the
process (also when it is killed): a stale ``.lock`` file locks nothing.
Where ``fcntl`` does not exist (Windows) runs are not locked.
"""

from __future__ import annotations

import os
from contextlib import contextmanager
from pathlib import Path

from ..errors import OutputError

__all__ = ["LOCK_NAME", "output_lock"]

#: The file of ``OUT`` that a running batch holds locked.
LOCK_NAME = ".lock"


@contextmanager
def output_lock(out: Path):
    """Hold ``out/.lock`` locked while the block runs.

    Raises
    ------
    OutputError
        Another process (another batch) holds it, or it cannot be created.
    """
    try:
        import fcntl
    except ImportError:  # pragma: no cover - Windows: no flock
        yield
        return
    path = Path(out) / LOCK_NAME
    try:
        fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o666)
    except OSError as exc:
        raise OutputError(f"Cannot create the lock file {path} ({exc.strerror}): give --out a folder that can "
                          "be written.") from None
    try:
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            raise OutputError(f"Another meshcorr batch is writing into {out} (it holds {path}): two runs into one "
                              "folder would overwrite each other's summary. Wait for it to end, or give another "
                              "--out.") from None
        yield
    finally:
        os.close(fd)  # releases the lock
