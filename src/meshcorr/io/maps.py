"""Vertex-map files: ``.npy`` (:func:`numpy.save`) or text with one integer per line.

A map ``mapping`` ``(n,)`` int sends source vertex ``i`` to target vertex
``mapping[i]`` (-1: unmapped); :func:`write_map` writes it atomically and
:func:`read_map` reads it back.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from ..errors import InputError
from ..runtime.checks import MapMessages, check_vertex_map
from .arrays import load_npy
from .files import atomic_write

__all__ = ["map_bytes", "map_text", "read_map", "write_map"]

#: The words of a map that :func:`write_map` refuses (:func:`meshcorr.runtime.checks.check_vertex_map`).
_WRITTEN_MAP = MapMessages(
    not_integer="The 'mapping' parameter of write_map must be a 1-D integer array. "
                "Got shape {shape} and dtype {dtype} instead.",
    wrong_length="", out_of_range="")  # write_map checks no vertex counts


def write_map(path, mapping) -> None:
    """Write a vertex map atomically: ``.npy`` with :func:`numpy.save`, else one integer per line.

    Parameters
    ----------
    path : str or os.PathLike
        Target file. ``.npy`` gives a NumPy file; any other extension
        (``.txt``, ``.map``, none) gives text with one integer per line.
    mapping : (n,) int
        The map, e.g. ``p2p_21[i]`` = vertex of mesh 1 matched to vertex ``i`` of mesh 2.
    """
    mapping = check_vertex_map(mapping, messages=_WRITTEN_MAP)
    if Path(path).suffix.lower() == ".npy":
        atomic_write(path, lambda file: np.save(file, mapping, allow_pickle=False))
    else:
        text = map_bytes(mapping)
        atomic_write(path, lambda file: file.write(text))


def map_text(mapping) -> str:
    """A vertex map as the text :func:`write_map` writes: one integer per line."""
    return map_bytes(mapping).decode("ascii")


def map_bytes(mapping) -> bytes:
    r"""``(n,)`` int -> the ASCII bytes of one integer a line, in one vectorised pass.

    Each value's decimal digits are the columns of an ``(n, w + 2)`` byte
    matrix (a sign column, ``w`` digit columns :math:`\lfloor |v| / 10^j
    \rfloor \bmod 10`, a newline column); a mask keeps the sign of negative
    values and the digits from the leading one on (the last digit always),
    and the kept bytes in row order are the text. Written out because no
    library call formats integers in one vectorised pass: at 1.28M lines this
    took 0.06-0.21 s, Python's per-value formatting 0.22-0.53 s and
    ``numpy.savetxt`` 2.7 s (2 shared cores).
    """
    values = np.asarray(mapping, dtype=np.int64).ravel()
    if not len(values):
        return b""
    magnitude = np.abs(values)
    width = len(str(int(magnitude.max())))
    powers = 10 ** np.arange(width - 1, -1, -1, dtype=np.int64)
    chars = np.empty((len(values), width + 2), dtype=np.uint8)
    keep = np.empty(chars.shape, dtype=bool)
    chars[:, 0], keep[:, 0] = ord("-"), values < 0
    rest = magnitude
    for column in range(width, 0, -1):  # one scalar divisor a column: numpy's fast division by a constant
        rest, digit = np.divmod(rest, 10)
        chars[:, column] = digit + ord("0")
    keep[:, 1:-1] = powers <= np.maximum(magnitude, 1)[:, None]
    chars[:, -1], keep[:, -1] = ord("\n"), True
    return chars[keep].tobytes()


def read_map(path, *, name: str | None = None) -> np.ndarray:
    """Read a vertex map written by :func:`write_map` (``.npy`` or one integer per line).

    Parameters
    ----------
    path : str or os.PathLike
        The map file. Blank lines in text files are ignored.
    name : str, optional
        What the file is, for messages (e.g. ``"MAP"``).

    Returns
    -------
    mapping : (n,) int64

    Raises
    ------
    InputError
        If the file is missing or unreadable, or does not hold a 1-D array
        of integers that fit an int64 (a :class:`ParameterError`).
    """
    path = Path(path)
    if not path.is_file():
        which = f" ({name})" if name else ""
        raise InputError(f"No such file: {path}{which}. Check the path." if not path.exists()
                         else f"Not a file: {path}{which}; give a map file.")
    if path.suffix.lower() == ".npy":
        try:
            mapping = load_npy(path)
        except ValueError as exc:
            raise InputError(f"{path}: could not be read as a .npy array ({exc}).") from exc
        if mapping.ndim != 1 or not np.issubdtype(mapping.dtype, np.integer):
            raise InputError(
                f"{path}: a map must be a 1-D integer array; got shape {mapping.shape} "
                f"and dtype {mapping.dtype}."
            )
        huge = np.flatnonzero(mapping > np.iinfo(np.int64).max)  # uint64: it wrapped to negatives (-1: unmapped)
        if huge.size:
            raise InputError(f"{path}: entry {int(huge[0])} is {int(mapping[huge[0]])}, too large for a vertex "
                             f"index (a {mapping.dtype} array). Write the map as int64, with -1 for an unmapped "
                             "vertex.")
        return mapping.astype(np.int64)
    try:
        lines = path.read_text(encoding="ascii").splitlines()
    except UnicodeDecodeError as exc:
        raise InputError(f"{path}: not a text file (byte {exc.start} is not ASCII); a map file is text with "
                         "one integer per line, or a .npy array.") from exc
    except OSError as exc:  # no read permission; a folder or a file gone since the check
        which = f" ({name})" if name else ""
        raise InputError(f"Cannot read the map file {path}{which}: {exc.strerror or exc}. Check that it is a "
                         "file you may read.") from exc
    numbered = [(i + 1, line.strip()) for i, line in enumerate(lines) if line.strip()]
    for number, line in numbered:
        if not re.fullmatch(r"[+-]?\d{1,18}", line):
            raise InputError(
                f"{path}, line {number}: expected one integer per line (at most 18 digits), got {line[:40]!r}."
            )
    return np.array([int(line) for _, line in numbered], dtype=np.int64)
