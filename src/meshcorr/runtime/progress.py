"""Ready-made ``progress(stage, done, total)`` reporters for :func:`meshcorr.match`.

- :class:`RunProgress`: how far a whole run is, a fraction from 0 to 1 that
  only rises, from the run's stage reports and a table of the stages'
  expected shares of its time (:data:`MATCH_PLAN`); and the time left.
- :class:`TqdmProgress`: one tqdm bar for the whole run, labelled with the
  running stage, with the time left; what ``progress=True`` gives. Needs
  ``pip install meshcorr[notebook]`` (tqdm).
- :class:`StderrProgress`: the command line's progress line on a stream
  (rewritten in place on a terminal), which ticks while a stage reports
  nothing.
- :func:`run_progress`: the ``with`` block of :func:`meshcorr.match` that
  turns its ``progress`` option into a callback and tells a ready-made
  reporter when the run has ended.

A user's own callback gets the stages' reports as they are: ``(stage, 0, 1)``
as a stage starts, ``(stage, 1, 1)`` as it ends and, from stages that count
their sub-steps, ``(stage, done, total)`` between the two. A stage may run
more than once in a run ("refine", "shells", "icp", "symmetry"), each time
with its own reports.
"""

from __future__ import annotations

import contextlib

import sys
import threading
import time
import weakref
from typing import NamedTuple

from ..errors import ParameterError

__all__ = ["MATCH_PLAN", "RunPlan", "RunProgress", "StderrProgress", "TqdmProgress", "as_progress",
           "format_duration", "run_progress"]


class RunPlan(NamedTuple):
    """The stages a run is expected to go through, in order, each with its share of the run's time.

    ``stages`` is the path a run starts on; ``paths`` maps the stage that
    opens another path (met only there, e.g. "coarse") to that path's stages,
    from the run's first stage on. Shares are relative (each path is
    normalised), a stage that runs several times has one entry per run.
    """

    stages: tuple[tuple[str, float], ...]
    paths: dict


#: Expected shares of a :func:`meshcorr.match` run's time, stage by stage in the order they run, for the
#: three paths a default run can take. Measured (seconds, default settings, one run each on a 2-core machine
#: busy with other work, so only their ratios mean anything) with a ``progress`` callback recording each
#: stage's start and end (per stage they add up to ``result.timings``):
#:
#: - matched on the meshes: two 8000-vertex creatures (``creature(resolution=5)`` at rest and at pose 0.4;
#:   9.2 s in all, of which 4.1 s the first "shells" and 2.2 s the second "refine"; the examples' pair,
#:   500 -> 1000 vertices, takes 1.3 s, a quarter of it in the geodesics);
#: - coarse-to-fine ("coarse": meshes above 4 x ``coarse_vertices``): two 64 000-vertex creatures
#:   (``creature(resolution=6)`` at rest and at pose 0.4, each subdivided once by trimesh; 111 s in all, of
#:   which 83 s the last "shells" and 20 s the two last "refine", on the meshes);
#: - large meshes (above :data:`meshcorr.stages.lift.LIFT_ABOVE` vertices, "large", the memory check, opens
#:   it): the Sumner lion pair subdivided to 1.28M vertices (``benchmarks/million.py``; 124 s in all, of which
#:   51 s the "lift", 25 s "coarse", 23 s "whole-map" and 15 s "load");
#: - a part against the whole (``partial="source"``, "whole-to-whole" opens it): the rest creature of
#:   resolution 2 cut by ``cut_by_plane(keep=0.7)`` against the posed one (2.5 s in all).
#:
#: Not every run meets every entry (prepared shapes skip "geodesics", ``refine=False`` the stages after
#: "matching", a baseline's stages are not listed): the fraction jumps over entries that do not run and
#: stays put through a stage with no entry left; the rest is filled when the run ends.
MATCH_PLAN = RunPlan(
    stages=(("load", 0.066), ("geodesics", 0.303), ("embedding", 0.021), ("geodesics", 0.389),
            ("embedding", 0.011), ("reorder", 0.176), ("symmetry", 0.043), ("icp", 0.278), ("symmetry", 0.178),
            ("matching", 0.238), ("refine", 0.0), ("refine", 2.223), ("whole-map", 0.994), ("shells", 4.148),
            ("shells", 0.0)),
    paths={
        "coarse": (("load", 0.51), ("coarse", 1.54), ("geodesics", 0.2), ("embedding", 0.01), ("geodesics", 0.15),
                   ("embedding", 0.01), ("reorder", 0.2), ("symmetry", 0.03), ("icp", 0.32), ("symmetry", 0.15),
                   ("matching", 0.21), ("refine", 0.0), ("refine", 0.09), ("whole-map", 2.46), ("shells", 2.72),
                   ("shells", 0.0), ("refine", 4.07), ("refine", 15.66), ("shells", 82.76)),
        "large": (("load", 14.5), ("large", 0.0), ("coarse", 25.1), ("geodesics", 0.11), ("embedding", 0.0),
                  ("geodesics", 0.11), ("embedding", 0.0), ("reorder", 0.11), ("symmetry", 0.04), ("icp", 0.16),
                  ("symmetry", 0.03), ("matching", 0.08), ("refine", 0.0), ("refine", 0.03), ("whole-map", 23.5),
                  ("shells", 8.2), ("shells", 0.0), ("lift", 50.7)),
        "whole-to-whole": (("load", 0.005), ("whole-to-whole", 1.731), ("extremities", 0.036),
                           ("candidates", 0.279), ("refine", 0.095), ("shells", 0.177), ("region", 0.002)),
    })


def format_duration(seconds: float) -> str:
    """``"42s"`` or ``"3m05s"``, as ``meshcorr batch`` writes durations."""
    seconds = int(round(seconds))
    return f"{seconds // 60}m{seconds % 60:02d}s" if seconds >= 60 else f"{seconds}s"


class RunProgress:
    """How far a run is: a fraction from 0 to 1 that never falls, from the run's stage reports.

    A stage that starts takes the next entry of its name in the plan
    (:class:`RunPlan`): the fraction moves to the entry's start (over the
    entries that did not run), the stage's sub-steps move it through the
    entry's share and the stage's end to the entry's end. A stage with no
    entry left (met more often than planned, or not in the plan) leaves the
    fraction where it is. While a stage that counts no sub-steps runs,
    :meth:`tick` moves the fraction through its share at the pace the run
    has had so far, up to :attr:`TIME_FILL` of it.

    Parameters
    ----------
    plan : RunPlan
    clock : callable, optional
        Seconds (default ``time.perf_counter``); tests pass a fake one.
    """

    #: The most of an entry's share that time alone (:meth:`tick`) fills; its end fills the rest.
    TIME_FILL = 0.9

    def __init__(self, plan: RunPlan = MATCH_PLAN, *, clock=time.perf_counter) -> None:
        self.plan, self.clock = plan, clock
        self.start = clock()
        self.fraction = 0.0
        self.stage: str | None = None  # the stage running; None between two stages
        self.label: str | None = None  # the last stage that started
        self._entries = self._normalised(plan.stages)
        self._path: str | None = None
        self._next = 0
        self._span: tuple[float, float] | None = None  # the running stage's entry, (start, end)
        self._since = self._pace = 0.0
        self._counted = False

    @staticmethod
    def _normalised(stages) -> list[tuple[str, float, float]]:
        total = sum(share for _, share in stages) or 1.0
        entries, low = [], 0.0
        for name, share in stages:
            entries.append((name, low, low + share / total))
            low += share / total
        return entries

    def update(self, stage: str, done: int, total: int) -> bool:
        """Take one ``progress(stage, done, total)`` report; True where a stage started or ended."""
        total = max(int(total), 1)
        done = min(max(int(done), 0), total)
        started = stage != self.stage
        if started:
            if done >= total:  # the end of a stage not running: its sub-steps ended it already
                return False
            self._begin(stage)
        if self._span is not None and (total > 1 or done == total):
            self._counted = self._counted or total > 1
            low, high = self._span
            self._advance(low + (high - low) * done / total)
        if done >= total:
            self.stage, self._span = None, None
            return True
        return started

    def _begin(self, stage: str) -> None:
        if stage in self.plan.paths and self._path is None:  # e.g. "coarse": the coarse-to-fine path (the first
            # path opened holds: "large" opens the large meshes' path before their "coarse")
            self._path, self._entries, self._next = stage, self._normalised(self.plan.paths[stage]), 0
        now = self.clock()
        self.stage = self.label = stage
        self._span, self._since, self._counted = None, now, False
        for index in range(self._next, len(self._entries)):
            name, low, high = self._entries[index]
            if name == stage:
                self._next, self._span = index + 1, (low, high)
                self._pace = (now - self.start) / low if low > 0 else 0.0  # seconds per whole run so far
                self._advance(low)
                break

    def _advance(self, fraction: float) -> None:
        self.fraction = min(1.0, max(self.fraction, fraction))

    def tick(self) -> None:
        """Move through the running stage's share by its time, where it counts no sub-steps."""
        if self._span is None or self._counted or self._pace <= 0:
            return
        low, high = self._span
        if high > low:
            spent = (self.clock() - self._since) / (self._pace * (high - low))
            self._advance(low + (high - low) * min(self.TIME_FILL, spent))

    def elapsed(self) -> float:
        """Seconds since the run started (since this object was made)."""
        return self.clock() - self.start

    def seconds_left(self) -> float | None:
        """The time so far scaled by the fraction left; None before 1 % of the run."""
        if self.fraction < 0.01:
            return None
        return self.elapsed() * (1.0 - self.fraction) / self.fraction

    def finish(self) -> None:
        """The run has ended: the fraction is 1."""
        self.fraction, self.stage, self._span = 1.0, None, None


def _tqdm():
    try:
        from tqdm.auto import tqdm
    except ImportError as exc:
        raise ParameterError("progress=True draws a tqdm bar: install it with "
                             "'pip install meshcorr[notebook]' (or pass a callable).") from exc
    return tqdm


class TqdmProgress:
    """One tqdm progress bar for a whole run, labelled with the running stage.

    The bar goes from 0 to 100 % over the run (:class:`RunProgress` with
    ``plan``), never back, and shows the time so far and tqdm's estimate of
    the time left (from the average pace). :meth:`finish` fills it;
    :func:`meshcorr.match` calls it as the run ends.

    Parameters
    ----------
    plan : RunPlan or None
        The run's stages and their shares (default :data:`MATCH_PLAN`). None:
        a bar per stage instead, filled by the stage's sub-steps (for the
        other callers of ``progress=True``, whose stages have no plan).
    **tqdm_options
        Passed to ``tqdm.auto.tqdm`` (e.g. ``leave=False``, ``file=``).

    Attributes
    ----------
    stages : list of str
        The stages in the order they started, a stage run again listed again.
    """

    #: The bar's look: the stage, the share done, the time so far and the time left.
    BAR_FORMAT = "{desc}: {percentage:3.0f}%|{bar}| [{elapsed}<{remaining}]"

    def __init__(self, plan: RunPlan | None = MATCH_PLAN, **tqdm_options) -> None:
        tqdm = _tqdm()
        self.run = None if plan is None else RunProgress(plan)
        if self.run is None:
            self.bar = tqdm(total=1, desc="meshcorr", unit="step", **tqdm_options)
        else:
            options = dict(bar_format=self.BAR_FORMAT, smoothing=0.0)  # smoothing 0: the average pace
            self.bar = tqdm(total=100, desc="meshcorr", **{**options, **tqdm_options})
        self.stages: list[str] = []

    def __call__(self, stage: str, done: int, total: int) -> None:
        if self.run is None:
            self._stage_bar(stage, done, total)
            return
        started = self.run.update(stage, done, total) and self.run.stage == stage
        if started:
            self.stages.append(stage)
            self.bar.set_description_str(f"meshcorr: {stage}", refresh=False)
        value = 100.0 * self.run.fraction
        if value > self.bar.n:
            self.bar.update(value - self.bar.n)  # tqdm limits the redraws
        elif started:
            self.bar.refresh()

    def _stage_bar(self, stage: str, done: int, total: int) -> None:
        total = max(int(total), 1)
        if not self.stages or self.stages[-1] != stage:
            self.stages.append(stage)
            self.bar.reset(total=total)
            self.bar.set_description(f"meshcorr: {stage}", refresh=False)
        elif total != self.bar.total:
            self.bar.reset(total=total)
        self.bar.update(min(int(done), total) - self.bar.n)

    def finish(self) -> None:
        """The run has ended: the bar is full."""
        if self.run is not None:
            self.run.finish()
            self.bar.set_description_str("meshcorr: done", refresh=False)
        self.bar.n = self.bar.total
        self.bar.refresh()

    def close(self) -> None:
        """End the bar (it stays on screen as a record of the run)."""
        self.bar.close()


def as_progress(progress, plan: RunPlan | None = None):
    """A progress callback from the ``progress`` option of :func:`meshcorr.match`.

    Parameters
    ----------
    progress : None, bool or callable
        None / False: no reporting; True: a new :class:`TqdmProgress` with
        ``plan``; a callable ``progress(stage, done, total)`` is returned as it is.
    plan : RunPlan, optional
        The plan of the bar that True makes (:data:`MATCH_PLAN` for a match);
        None: a bar per stage.

    Raises
    ------
    ParameterError
        For anything else.
    """
    if progress is None or progress is False:
        return None
    if progress is True:
        return TqdmProgress(plan)
    if not callable(progress):
        raise ParameterError("The 'progress' parameter must be True, False, None or a callable "
                             f"progress(stage, done, total). Got {progress!r} instead.")
    return progress


@contextlib.contextmanager
def run_progress(progress):
    """The reporter of one run with a ``progress`` option (:func:`meshcorr.match`), as a ``with`` block.

    ``progress`` becomes a callback (:func:`as_progress` with
    :data:`MATCH_PLAN`). A ready-made reporter (:class:`TqdmProgress`,
    :class:`StderrProgress`) is finished when the block ends and closed when
    it raises; one made here from ``progress=True`` is closed in both cases.
    A user's own callback is only called by the stages. A block, not a
    decorator: the run's warnings keep pointing at its caller's line.
    """
    reporter = as_progress(progress, MATCH_PLAN)
    ready_made = isinstance(reporter, (TqdmProgress, StderrProgress))
    try:
        yield reporter
        if ready_made:
            reporter.finish()
    except BaseException:
        if ready_made:
            reporter.close()
        raise
    if ready_made and reporter is not progress:
        reporter.close()


class StderrProgress:
    """A ``progress(stage, done, total)`` callback writing progress lines to a stream (stderr by default).

    The command line's reporter (``meshcorr match``, ``evaluate``, ``show``,
    ``embed``). Each line starts with ``label`` (which meshes the run is on),
    so that lines of several runs can be told apart. On a terminal the line
    is rewritten in place; elsewhere (a log) each is a line of its own.

    With a ``plan`` (``meshcorr match``: :data:`MATCH_PLAN`), one line for the
    whole run, as ``meshcorr batch`` writes its own::

        meshcorr: a.off -> b.off [shells] [###############---------] 63%, 1m12s, ~40s left

    from ``delay`` seconds into the run on: the running stage, a bar and the
    share of the run done (:class:`RunProgress`: it only rises), the time so
    far and an estimate of the time left. ``verbose`` adds a line as each
    stage ends, ``[stage] done in 1.2 s``; :meth:`finish` writes the full line.

    Without a plan, a line per stage: a stage is announced once it has run
    for ``delay`` seconds, then its share done (``[stage] 42% 3 s``, rising)
    and, if it was announced (``delay=0``: every stage), its end with its
    duration.

    In both, a background thread (started by the first report, stopped by
    :meth:`close` or :meth:`finish`) writes the line again after ``tick``
    seconds without one, so that a stage that reports nothing is never
    silent for long. Call :meth:`close` when the run ends, also on an error.

    Parameters
    ----------
    stream : file, optional
    label : str
    delay : float
        Seconds before the first line (of the run, or of a stage without plan).
    interval : float
        Fewest seconds between two lines of sub-steps.
    plan : RunPlan, optional
    verbose : bool
        With a plan: a line as each stage ends.
    tick : float, optional
        Seconds without a line after which the line is written again
        (default 1 on a terminal, 5 elsewhere).
    clock : callable, optional
        Seconds (default ``time.perf_counter``); tests pass a fake one.
    """

    #: Width of the bar, in characters (as ``meshcorr batch``).
    WIDTH = 24

    def __init__(self, stream=None, *, label: str = "", delay: float = 1.0, interval: float = 0.5,
                 plan: RunPlan | None = None, verbose: bool = False, tick: float | None = None,
                 clock=time.perf_counter) -> None:
        self.stream = stream if stream is not None else sys.stderr
        self.prefix = f"meshcorr: {label} " if label else ""
        self.delay, self.interval, self.plan, self.verbose, self.clock = delay, interval, plan, verbose, clock
        self.tty = hasattr(self.stream, "isatty") and self.stream.isatty()
        self.tick = tick if tick is not None else (1.0 if self.tty else 5.0)
        self.run: RunProgress | None = None
        self._lock = threading.RLock()
        self._ticker: threading.Thread | None = None
        self._stop = threading.Event()
        self._open_line = False  # a terminal line written without its newline
        self._last = 0.0  # when the last line was written
        self._stage: str | None = None  # without plan: the stage running, its start, its last report
        self._start = 0.0
        self._done = (0, 1)
        self._shown = False
        self._wrote = False  # a line was written (in this run)

    def __call__(self, stage: str, done: int, total: int) -> None:
        with self._lock:
            self._start_ticker()
            if self.plan is not None:
                self._run_report(stage, done, total)
            else:
                self._stage_report(stage, done, total)

    # -- with a plan: one line for the run

    def _run_report(self, stage: str, done: int, total: int) -> None:
        now = self.clock()
        if self.run is None:
            self.run, self._wrote = RunProgress(self.plan, clock=self.clock), False
        running, since = self.run.stage, self._start
        if not self.run.update(stage, done, total):  # a sub-step: a line at most every `interval`
            self._run_line(now)
            return
        if self.run.stage is None:  # the stage ended
            if running is not None and self.verbose:
                self._write(f"[{running}] done in {now - since:.1f} s", end=True)
            if self.tty:
                self._run_line(now, force=True)
            return
        self._start = now  # a stage started: said at once
        self._run_line(now, force=True)

    def _run_line(self, now: float, force: bool = False, end: bool = False) -> None:
        run = self.run
        if run is None or (run.elapsed() < self.delay and not end):
            return
        if not (force or end or now - self._last >= self.interval):
            return
        filled = int(self.WIDTH * run.fraction)
        left = run.seconds_left()
        text = (f"[{'done' if end else run.label or 'start'}] [{'#' * filled}{'-' * (self.WIDTH - filled)}] "
                f"{100 * run.fraction:3.0f}%, {format_duration(run.elapsed())}"
                + ("" if left is None or end else f", ~{format_duration(left)} left"))
        self._write(text, end=end or not self.tty)

    # -- without a plan: a line per stage

    def _stage_report(self, stage: str, done: int, total: int) -> None:
        now = self.clock()
        total = max(int(total), 1)
        if stage != self._stage or done < self._done[0] * total / self._done[1]:  # a new stage, or run again
            if self._open_line:
                self._end_line()
            self._stage, self._start, self._last, self._shown = stage, now, now, False
        self._done = (min(int(done), total), total)
        elapsed = now - self._start
        if done >= total and total == 1 and done == 1:
            if self._shown or elapsed >= self.delay:
                self._write(f"[{stage}] done in {elapsed:.1f} s", end=True)
            self._stage, self._done = None, (0, 1)
            return
        if elapsed < self.delay or (now - self._last < self.interval and done < total):
            return
        self._stage_line(now)

    def _stage_line(self, now: float) -> None:
        done, total = self._done
        self._shown = True
        pct = f" {100 * done / total:3.0f}%" if total > 1 else ""
        self._write(f"[{self._stage}]{pct} {now - self._start:.0f} s", end=not self.tty)

    # -- the ticks, the end

    def _tick(self) -> None:
        with self._lock:
            now = self.clock()
            if now - self._last < self.tick:
                return
            if self.plan is None:  # a stage running, not yet through its sub-steps
                if self._stage is not None and self._done[0] < self._done[1] and now - self._start >= self.delay:
                    self._stage_line(now)
            elif self.run is not None:
                self.run.tick()
                self._run_line(now, force=True)

    def _start_ticker(self) -> None:
        if self._ticker is None:
            self._stop = threading.Event()
            self._ticker = threading.Thread(target=_tick_lines, args=(weakref.ref(self), self._stop,
                                                                      min(0.5, self.tick)),
                                            name="meshcorr-progress", daemon=True)
            self._ticker.start()

    def finish(self) -> None:
        """The run has ended: with a plan, the full line (if any line was written); then :meth:`close`."""
        with self._lock:
            if self.plan is not None and self.run is not None:
                self.run.finish()
                if self._wrote or self.verbose:
                    self._run_line(self.clock(), end=True)
                self.run = None  # a further report starts a new run
        self.close()

    def close(self) -> None:
        """Stop the ticks (the thread ends before this returns) and end the terminal line; again: nothing."""
        ticker, self._ticker = self._ticker, None
        if ticker is not None:
            self._stop.set()
            if ticker is not threading.current_thread():
                ticker.join()
        with self._lock:
            if self._open_line:
                self._end_line()

    def _end_line(self) -> None:
        self.stream.write("\n")
        self.stream.flush()
        self._open_line = False

    def _write(self, text: str, end: bool) -> None:
        text = self.prefix + text
        if self.tty:
            self.stream.write("\r\033[K" + text + ("\n" if end else ""))
            self._open_line = not end
        else:
            self.stream.write(text + "\n")
        self.stream.flush()
        self._last, self._wrote = self.clock(), True


def _tick_lines(reporter_ref, stop: threading.Event, poll: float) -> None:
    """The ticker thread of a :class:`StderrProgress`: its ticks until stopped or the reporter is gone."""
    while not stop.wait(poll):
        reporter = reporter_ref()
        if reporter is None:
            return
        try:
            reporter._tick()
        except (OSError, ValueError):  # the stream was closed: no more lines
            return
        finally:
            del reporter
