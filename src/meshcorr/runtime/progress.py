"""Ready-made ``progress(stage, done, total)`` reporters for :func:`meshcorr.match`.

- :class:`TqdmProgress`: a tqdm bar, notebook-aware (``tqdm.auto``); what
  ``progress=True`` gives. Needs ``pip install meshcorr[notebook]`` (tqdm).
- :class:`StderrProgress`: the command line's progress lines on a stream.
"""

from __future__ import annotations

from ..errors import ParameterError

__all__ = ["StderrProgress", "TqdmProgress", "as_progress"]


def __getattr__(name: str):
    if name == "StderrProgress":  # the command line's reporter, imported when asked for
        from ..cli._progress import StageProgress

        return StageProgress
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


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
