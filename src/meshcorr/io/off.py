"""A strict reader of ASCII OFF files: every count and every record checked against the header.

The OFF format (Geomview): a keyword line (``OFF``, or ``COFF``, ``NOFF``,
``STOFF``, ... whose extra per-vertex values are ignored), the counts
``n_vertices n_faces n_edges``, then ``n_vertices`` lines of at least three
coordinates and ``n_faces`` lines ``k i_1 ... i_k [colour]``. ``#`` starts a
comment, in any encoding; outside comments the file must be ASCII.

Refused, with the line where it applies: a missing or non-numeric header,
binary OFF, counts larger than the file's line count, fewer vertex or face
lines than the header declares (a truncated file), more lines than it declares, a vertex with fewer than
three numbers or a non-finite one, a face with fewer than three vertices,
fewer indices than its arity or an index outside ``[0, n_vertices)``.
Faces with more than three sides are split into a fan of triangles
``(i_1, i_j, i_j+1)``; the caller warns about them.
"""

from __future__ import annotations

import numpy as np

from ..errors import MeshError

__all__ = ["parse_off"]

_FIX = "Re-export the mesh (e.g. from MeshLab) or repair the file."


def _records(data: bytes):
    """(line number, tokens) of each line with data, comments removed."""
    for number, line in enumerate(data.splitlines(), start=1):
        tokens = line.split(b"#", 1)[0].split()
        if tokens:
            yield number, tokens


def _fail(label: str, number: int | None, problem: str, fix: str = _FIX) -> MeshError:
    where = f"{label}, line {number}" if number is not None else label
    return MeshError(f"{where}: {problem}. {fix}")


def _ascii(label: str, number: int, tokens: list[bytes]) -> list[bytes]:
    if not all(token.isascii() for token in tokens):
        raise _fail(label, number, "holds non-ASCII bytes outside a comment (OFF data must be ASCII "
                                   "text; is this a binary file?)")
    return tokens


def _header(label: str, records) -> tuple[int, int, int]:
    """(n_vertices, n_faces, line number of the counts) from the keyword and the counts."""
    try:
        number, tokens = next(records)
    except StopIteration:
        raise _fail(label, None, "holds only comments, no OFF header") from None
    tokens = _ascii(label, number, tokens)
    keyword = tokens[0].upper()
    if not keyword.endswith(b"OFF"):
        raise _fail(label, number, f"expected the OFF keyword, got {tokens[0][:20].decode()!r}",
                    "Check that it is an OFF file (the first line reads OFF).")
    if b"4" in tokens[0][:-3] or b"n" in tokens[0][:-3]:  # 4OFF, nOFF: other dimensions
        raise _fail(label, number, f"the {tokens[0].decode()} variant is not supported (only 3-D OFF)",
                    "Convert it to a plain OFF or PLY file.")
    counts = tokens[1:]
    if counts[:1] == [b"BINARY"]:
        raise _fail(label, number, "binary OFF is not supported", "Save the mesh as ASCII OFF, PLY or OBJ.")
    if not counts:
        try:
            number, counts = next(records)
        except StopIteration:
            raise _fail(label, number, "the file ends after the OFF keyword, before the vertex "
                                       "and face counts") from None
        counts = _ascii(label, number, counts)
    try:
        n_vertices, n_faces = int(counts[0]), int(counts[1])
    except (IndexError, ValueError):
        raise _fail(label, number, "expected the counts 'n_vertices n_faces n_edges', got "
                                   f"{b' '.join(counts)[:40].decode()!r}") from None
    if n_vertices < 0 or n_faces < 0:
        raise _fail(label, number, f"negative counts {n_vertices} {n_faces}")
    return n_vertices, n_faces, number


def _check_size(label: str, data: bytes, n_vertices: int, n_faces: int, header_line: int) -> None:
    """Refuse a vertex count the file cannot hold (one record a line) before allocating for it.

    Smaller shortfalls are reported where the data ends, by the record loops.
    """
    n_lines = data.count(b"\n") + 1
    if n_vertices > n_lines:
        raise _fail(label, header_line, f"the header declares {n_vertices} vertices and {n_faces} faces, "
                                        f"but the file has only {n_lines} lines: it is truncated or the "
                                        "header is wrong")


def _next_record(label: str, records, last: int, done: str) -> tuple[int, list[bytes]]:
    """The next (line number, ASCII tokens); the end of the file here means it is truncated."""
    try:
        number, tokens = next(records)
    except StopIteration:
        raise _fail(label, last, f"the file ends after {done} its header declares: it is truncated") from None
    return number, _ascii(label, number, tokens)


def parse_off(data: bytes, label: str) -> tuple[np.ndarray, np.ndarray, int, int]:
    """Vertices, triangles, and the polygon and face counts of an ASCII OFF file.

    Parameters
    ----------
    data : bytes
        The file's content.
    label : str
        How messages name the file.

    Returns
    -------
    vertices : (n, 3) float64
        In file order.
    faces : (m, 3) int64
        Triangles, polygons split into fans.
    n_polygons : int
        Faces of the file with more than three sides.
    n_records : int
        Faces of the file (its header's count).

    Raises
    ------
    MeshError
        On any of the refusals listed in the module docstring, naming the line.
    """
    records = _records(data)
    n_vertices, n_faces, header_line = _header(label, records)
    _check_size(label, data, n_vertices, n_faces, header_line)
    vertices = np.empty((n_vertices, 3))
    last = header_line
    for row in range(n_vertices):
        number, tokens = _next_record(label, records, last, f"{row} of the {n_vertices} vertices")
        last = number
        if len(tokens) < 3:
            raise _fail(label, number, f"vertex {row} has {len(tokens)} coordinates, not 3 (a truncated line?)")
        try:
            vertices[row] = [float(t) for t in tokens[:3]]
        except ValueError:
            raise _fail(label, number, f"vertex {row}: expected three numbers, got "
                                       f"{b' '.join(tokens)[:40].decode()!r}") from None
    if not np.isfinite(vertices).all():
        row = int(np.flatnonzero(~np.isfinite(vertices).all(axis=1))[0])
        raise _fail(label, None, f"vertex {row} has a non-finite coordinate (nan or inf)")
    triangles: list[list[int]] = []
    n_polygons = 0
    for face in range(n_faces):
        number, tokens = _next_record(label, records, last, f"{face} of the {n_faces} faces")
        last = number
        try:
            arity = int(tokens[0])
            indices = [int(t) for t in tokens[1:1 + arity]]
        except ValueError:
            raise _fail(label, number, f"face {face}: expected 'k i_1 ... i_k' with integers, got "
                                       f"{b' '.join(tokens)[:40].decode()!r}") from None
        if arity < 3:
            raise _fail(label, number, f"face {face} has {arity} vertices; a face needs at least 3")
        if len(indices) < arity:
            raise _fail(label, number, f"face {face} declares {arity} vertices but lists {len(indices)} "
                                       "(a truncated line?)")
        outside = [i for i in indices if not 0 <= i < n_vertices]
        if outside:
            raise _fail(label, number, f"face {face} refers to vertex {outside[0]}, outside the "
                                       f"{n_vertices} vertices of the file (indices are 0-based)")
        if arity > 3:
            n_polygons += 1
        triangles.extend([indices[0], indices[j], indices[j + 1]] for j in range(1, arity - 1))
    extra = next(records, None)
    if extra is not None:
        raise _fail(label, extra[0], f"data after the {n_vertices} vertices and {n_faces} faces the header "
                                     "declares (a wrong header, or two files joined?)")
    return vertices, np.array(triangles, dtype=np.int64).reshape(-1, 3), n_polygons, n_faces
