"""Errors as one line of a table: a failed run of ``meshcorr bench`` or ``meshcorr batch`` is a row, not a stop.

The row keeps the error's type and message in one line of at most
:data:`ONE_LINE_LENGTH` characters (runs of white space made one space), so
that ``results.csv`` and ``summary.csv`` stay one row per run.
"""

from __future__ import annotations

#: The most characters :func:`one_line` keeps.
ONE_LINE_LENGTH = 300


def one_line(exc: BaseException) -> str:
    """``"TypeName: message"`` of ``exc`` on one line, cut to :data:`ONE_LINE_LENGTH` characters."""
    text = " ".join(str(exc).split())
    return f"{type(exc).__name__}: {text}"[:ONE_LINE_LENGTH]
