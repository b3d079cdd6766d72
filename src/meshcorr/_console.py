"""The ``meshcorr`` console script: Ctrl-C is clean from the first moment.

Loading the command line's modules (numpy, scipy, the pipeline) takes about
half a second; :mod:`meshcorr.cli` installs its interrupt handling only once
loaded. An interrupt before then ends the run here, as any later one does
(exit 130, no traceback); nothing has been written yet.
"""

from __future__ import annotations

import sys

#: The exit code of an interrupted run (128 + SIGINT), as :data:`meshcorr.cli.exits.EXIT_INTERRUPTED`.
EXIT_INTERRUPTED = 130


def main(argv: list[str] | None = None) -> int:
    try:
        from .cli import main as run
    except KeyboardInterrupt:
        return _interrupted()
    except ImportError as error:  # numpy turns an interrupt during its own import into an ImportError
        if _caused_by_interrupt(error):
            return _interrupted()
        raise
    return run(argv)


def _interrupted() -> int:
    print("meshcorr: interrupted", file=sys.stderr)
    return EXIT_INTERRUPTED


def _caused_by_interrupt(error: BaseException) -> bool:
    """Whether a KeyboardInterrupt is in ``error``'s chain of causes and contexts."""
    seen: set[int] = set()
    while error is not None and id(error) not in seen:
        if isinstance(error, KeyboardInterrupt):
            return True
        seen.add(id(error))
        error = error.__cause__ or error.__context__
    return False
