"""Stage timing, peak memory per stage and progress forwarding shared by every pipeline.

The peak memory of a stage is the peak resident set of the process while it
ran: on Linux the kernel's high-water mark (``VmHWM`` of
``/proc/self/status``) is reset when the stage starts (writing ``5`` to
``/proc/self/clear_refs``, Linux >= 4.0) and read when it ends. Elsewhere,
or where the file cannot be written, no stage memory is recorded.
"""

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
        #: Peak resident MiB of the process while each stage ran (the largest of its runs; Linux only).
        self.memory: dict[str, float] = {}

    @contextmanager
    def stage(self, name: str):
        if self.progress is not None:
            self.progress(name, 0, 1)
        reset_peak()
        start = time.perf_counter()
        try:
            yield
        finally:
            self.timings[name] = self.timings.get(name, 0.0) + time.perf_counter() - start
            peak = peak_resident_mib()
            if peak is not None:
                self.memory[name] = max(self.memory.get(name, 0.0), peak)
        if self.progress is not None:
            self.progress(name, 1, 1)

    def reporter(self, name: str):
        """A ``(done, total)`` callback for a stage, or None without a progress callback."""
        if self.progress is None:
            return None
        return lambda done, total: self.progress(name, done, total)


def reset_peak() -> None:
    """Reset the process's peak resident set (Linux); nothing elsewhere."""
    try:
        with open("/proc/self/clear_refs", "w") as file:
            file.write("5")
    except OSError:
        pass


def peak_resident_mib() -> float | None:
    """The process's peak resident set in MiB since the last reset (``VmHWM``), or None off Linux."""
    try:
        with open("/proc/self/status") as file:
            for line in file:
                if line.startswith("VmHWM:"):
                    return int(line.split()[1]) / 1024
    except (OSError, ValueError, IndexError):
        return None
    return None
