"""Ready-made ``progress(stage, done, total)`` reporters for :func:`meshcorr.match`.

- :class:`TqdmProgress`: a tqdm bar, notebook-aware (``tqdm.auto``); what
  ``progress=True`` gives. Needs ``pip install meshcorr[notebook]`` (tqdm).
- :class:`StderrProgress`: the command line's progress lines on a stream:
  a stage is announced once it has run for a second, then its share done.
"""

from __future__ import annotations

import sys
import time

from ..errors import ParameterError

__all__ = ["StderrProgress", "TqdmProgress", "as_progress"]


class TqdmProgress:
    """A tqdm progress bar whose label is the running stage.

    Stages that report sub-steps (e.g. geodesic solves: ``done`` of
    ``total``) fill the bar; the others show their name and the time.

    Parameters
    ----------
    **tqdm_options
        Passed to ``tqdm.auto.tqdm`` (e.g. ``leave=False``, ``file=``).
    """

    def __init__(self, **tqdm_options) -> None:
        try:
            from tqdm.auto import tqdm
        except ImportError as exc:
            raise ParameterError("progress=True draws a tqdm bar: install it with "
                                 "'pip install meshcorr[notebook]' (or pass a callable).") from exc
        self.bar = tqdm(total=1, desc="meshcorr", unit="step", **tqdm_options)
        self.stages: list[str] = []

    def __call__(self, stage: str, done: int, total: int) -> None:
        total = max(int(total), 1)
        if not self.stages or self.stages[-1] != stage:
            self.stages.append(stage)
            self.bar.reset(total=total)
            self.bar.set_description(f"meshcorr: {stage}", refresh=False)
        elif total != self.bar.total:
            self.bar.reset(total=total)
        self.bar.update(min(int(done), total) - self.bar.n)  # tqdm limits the redraws

    def close(self) -> None:
        """End the bar (it stays on screen as a record of the run)."""
        self.bar.close()


def as_progress(progress):
    """A progress callback from the ``progress`` option of :func:`meshcorr.match`.

    Parameters
    ----------
    progress : None, bool or callable
        None / False: no reporting; True: a new :class:`TqdmProgress`;
        a callable ``progress(stage, done, total)`` is returned as it is.

    Raises
    ------
    ParameterError
        For anything else.
    """
    if progress is None or progress is False:
        return None
    if progress is True:
        return TqdmProgress()
    if not callable(progress):
        raise ParameterError("The 'progress' parameter must be True, False, None or a callable "
                             f"progress(stage, done, total). Got {progress!r} instead.")
    return progress


class StderrProgress:
    """A ``progress(stage, done, total)`` callback printing progress lines to a stream (stderr by default).

    The command line's reporter (``meshcorr match``, ``batch``, ``bench``).

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
