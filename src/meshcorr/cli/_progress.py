"""Progress lines on stderr for stages that take more than a second."""

from __future__ import annotations

import sys
import time


class StageProgress:
    """A ``progress(stage, done, total)`` callback printing to a stream.

    A stage is announced only once it has run for ``delay`` seconds; its
    completion is printed with its duration if it was announced (``delay=0``:
    every stage, as ``-v`` asks). Each line starts with ``label`` (which
    meshes the run is on), so that lines of several runs can be told apart.
    """

    def __init__(self, stream=None, *, label: str = "", delay: float = 1.0, interval: float = 0.5) -> None:
        self.stream = stream if stream is not None else sys.stderr
        self.prefix = f"meshcorr: {label} " if label else ""
        self.delay, self.interval = delay, interval
        self.tty = hasattr(self.stream, "isatty") and self.stream.isatty()
        self._stage: str | None = None
        self._start = self._last = 0.0
        self._shown = False

    def __call__(self, stage: str, done: int, total: int) -> None:
        now = time.perf_counter()
        if stage != self._stage:
            self._stage, self._start, self._last, self._shown = stage, now, now, False
        elapsed = now - self._start
        if done >= total and total == 1 and done == 1:
            if self._shown or elapsed >= self.delay:
                self._write(f"[{stage}] done in {elapsed:.1f} s", end=True)
            self._stage = None
            return
        if elapsed < self.delay or (now - self._last < self.interval and done < total):
            return
        self._last = now
        self._shown = True
        pct = f" {100 * done / total:3.0f}%" if total > 1 else ""
        self._write(f"[{stage}]{pct} {elapsed:.0f} s", end=not self.tty)

    def _write(self, text: str, end: bool) -> None:
        text = self.prefix + text
        if self.tty:
            self.stream.write("\r\033[K" + text + ("\n" if end else ""))
        else:
            self.stream.write(text + "\n")
        self.stream.flush()
