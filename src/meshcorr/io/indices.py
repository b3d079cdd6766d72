"""Plain-text index files: ground truths, landmarks, vertex maps as text.

Each data line holds whole numbers (vertex indices) separated by spaces,
commas, colons or semicolons; ``#`` starts a comment and blank lines are
skipped. :func:`read_index_lines` gives the data lines with their numbers
(for messages that name a line), :func:`index_fields` the numbers of one.
"""

from __future__ import annotations

import re
from pathlib import Path

from ..errors import InputError

__all__ = ["index_fields", "read_index_lines"]


def read_index_lines(path: Path, kind: str = "ground-truth") -> list[tuple[int, str]]:
    """The non-blank lines of a plain-text index file, ``#`` comments removed, with their numbers.

    Raises :class:`InputError` naming ``kind`` for a missing, unreadable (no
    permission, a folder) or non-text file; an empty list for a file with no data lines.
    """
    if not path.is_file():
        raise InputError(f"No such {kind} file: {path}" if not path.exists()
                         else f"Not a file: {path} is a folder (or a device); give the {kind} file.")
    try:
        text = path.read_text(encoding="ascii")
    except UnicodeDecodeError as exc:
        raise InputError(f"{path}: a {kind} file must be plain text (byte {exc.start} is not ASCII).") from exc
    except OSError as exc:  # no read permission; a folder or a file gone since the check
        raise InputError(f"Cannot read the {kind} file {path}: {exc.strerror or exc}. Check that it is a file "
                         "you may read.") from exc
    lines = [(number, line.split("#", 1)[0].strip()) for number, line in enumerate(text.splitlines(), 1)]
    return [(number, line) for number, line in lines if line]


def index_fields(line: str) -> list[int] | None:
    """The integers of a line split at spaces, commas, colons or semicolons; None if one is not an integer."""
    fields = [f for f in re.split(r"[\s,:;]+", line) if f]
    if not all(re.fullmatch(r"[+-]?\d{1,18}", f) for f in fields):
        return None
    return [int(f) for f in fields]
