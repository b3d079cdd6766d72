"""The pair lists of a batch: a file of "SOURCE TARGET" lines, every ordered pair, or a template onto each shape.

Each is a list of ``(source, target)`` mesh paths for
:func:`meshcorr.collection.batch.batch`; :func:`map_name` is the file each
pair's map is written to.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Sequence

from ..errors import ParameterError

__all__ = ["all_pairs", "map_name", "read_pair_list", "template_pairs"]


def read_pair_list(path) -> list[tuple[str, str]]:
    """``(source, target)`` paths from a file of one "SOURCE TARGET" pair a line.

    Blank lines and lines starting with ``#`` are skipped; relative paths are
    relative to the file's folder.

    Raises
    ------
    ParameterError
        A missing file, or a line without exactly two paths.
    """
    path = Path(path)
    if not path.is_file():
        raise ParameterError(f"The pairs file {path} does not exist.")
    pairs = []
    for number, line in enumerate(path.read_text().splitlines(), start=1):
        words = line.split()
        if not words or words[0].startswith("#"):
            continue
        if len(words) != 2:
            raise ParameterError(f"{path}, line {number}: expected two mesh paths 'SOURCE TARGET', got "
                                 f"{line.strip()!r}. Quote nothing; paths with spaces are not supported.")
        pairs.append(tuple(str(path.parent / w) if not os.path.isabs(w) else w for w in words))
    if not pairs:
        raise ParameterError(f"The pairs file {path} lists no pairs.")
    return pairs


def all_pairs(shapes: Sequence[str]) -> list[tuple[str, str]]:
    """Every ordered pair ``(a, b)``, ``a != b``, of ``shapes``: ``n (n - 1)`` maps."""
    _check_shapes(shapes, 2)
    return [(a, b) for a in shapes for b in shapes if a != b]


def template_pairs(template: str, shapes: Sequence[str]) -> list[tuple[str, str]]:
    """``(template, shape)`` for each shape: maps from the template's vertices onto each shape."""
    _check_shapes(shapes, 1)
    return [(template, s) for s in shapes if s != template]


def _check_shapes(shapes: Sequence[str], minimum: int) -> None:
    if not shapes:
        raise ParameterError(f"No mesh files were given: list at least {minimum} "
                             f"({'after --all-pairs' if minimum > 1 else 'after --template T'}).")
    if len(set(shapes)) < minimum or len(set(shapes)) != len(shapes):
        raise ParameterError(f"Give at least {minimum} distinct mesh file{'s' if minimum > 1 else ''} (each "
                             f"once). Got {list(shapes)}.")


def map_name(source: str, target: str) -> str:
    """File name of the map of a pair: ``SOURCESTEM__TARGETSTEM.txt``."""
    return f"{Path(source).stem}__{Path(target).stem}.txt"
