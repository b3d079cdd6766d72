"""The ``meshcorr`` console script: Ctrl-C is clean from the first moment.

Loading the command line's modules (numpy, scipy, the pipeline) takes about
half a second; :mod:`meshcorr.cli` installs its interrupt handling only once
loaded. An interrupt before then ends the run here, as any later one does
(exit 130, no traceback); nothing has been written yet.
"""

from __future__ import annotations

import sys

#: The exit code of an interrupted run (128 + SIGINT), as :data:`meshcorr.cli.EXIT_INTERRUPTED`.
EXIT_INTERRUPTED = 130


def main(argv: list[str] | None = None) -> int:
    try:
        from .cli import main as run
    except KeyboardInterrupt:
        print("meshcorr: interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED
    return run(argv)
