"""Stage timing and progress forwarding shared by every pipeline."""

from __future__ import annotations

import time
from contextlib import contextmanager
from typing import Callable

#: ``progress(stage, done, total)``: called as long stages advance.
StageProgress = Callable[[str, int, int], None]


class StageTimer:
    """Times named stages and forwards progress to an optional callback.

    Examples
    --------
    >>> timer = StageTimer(None)
    >>> with timer.stage("geodesics"):
    ...     pass
    >>> sorted(timer.timings)
    ['geodesics']
    """

    def __init__(self, progress: StageProgress | None = None) -> None:
        self.progress = progress
        self.timings: dict[str, float] = {}

    @contextmanager
    def stage(self, name: str):
        if self.progress is not None:
            self.progress(name, 0, 1)
        start = time.perf_counter()
        try:
            yield
        finally:
            self.timings[name] = self.timings.get(name, 0.0) + time.perf_counter() - start
        if self.progress is not None:
            self.progress(name, 1, 1)

    def reporter(self, name: str):
        """A ``(done, total)`` callback for a stage, or None without a progress callback."""
        if self.progress is None:
            return None
        return lambda done, total: self.progress(name, done, total)
