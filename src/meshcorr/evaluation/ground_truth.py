"""Ground-truth correspondences: reading them from the formats in use.

A ground truth is a list of point pairs ``(source vertex, target vertex)``,
0-based, possibly sparse (feature points) and possibly with repeats (TOSCA's
template samples). Three sources are understood:

``"identity"``
    Vertex i of the source corresponds to vertex i of the target (meshes with
    one connectivity, e.g. poses of one Sumner animal).
A pair of ``.vts`` files (the TOSCA / SHREC format)
    Line k of ``A.vts`` is the **1-based** vertex of A that matches template
    sample k; likewise for B, so ``(vtsA[k] - 1, vtsB[k] - 1)`` is a pair.
    ``B.sym.vts`` in place of ``B.vts`` gives the left/right mirrored truth
    (Ren et al. 2018).
A text file of **0-based** vertex pairs
    One pair ``i j`` per line (separated by spaces, a comma or a colon; ``#``
    starts a comment), or one index per line: a dense map, line i holding the
    target vertex of source vertex i (the format ``meshcorr match`` writes).
"""

from __future__ import annotations

import os
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Sequence

import numpy as np

from ..errors import InputError
from ..io.indices import index_fields, read_index_lines

__all__ = ["GroundTruth", "identity_truth", "load_ground_truth", "read_pairs", "read_vts"]


@dataclass(frozen=True)
class GroundTruth:
    """Corresponding vertex pairs between a source and a target mesh.

    Attributes
    ----------
    source : (p,) int64
        Source vertex of each pair, 0-based.
    target : (p,) int64
        Its true target vertex, 0-based.
    description : str
        Where the pairs came from, for messages and reports.
    """

    source: np.ndarray
    target: np.ndarray
    description: str = ""

    def __post_init__(self) -> None:
        source = np.array(self.source, dtype=np.int64).reshape(-1)
        target = np.array(self.target, dtype=np.int64).reshape(-1)
        if source.shape != target.shape:
            raise InputError(
                f"A ground truth needs as many source as target vertices; got {source.size} "
                f"and {target.size}{self._where()}."
            )
        for array in (source, target):
            array.flags.writeable = False
        object.__setattr__(self, "source", source)
        object.__setattr__(self, "target", target)

    def _where(self) -> str:
        return f" in {self.description}" if self.description else ""

    def __len__(self) -> int:
        return int(self.source.size)

    def check(self, n_source: int, n_target: int) -> "GroundTruth":
        """Raise :class:`ParameterError` unless every index fits the meshes; return self."""
        for side, values, n in (("source", self.source, n_source), ("target", self.target, n_target)):
            bad = (values < 0) | (values >= n)
            if bad.any():
                first = int(np.flatnonzero(bad)[0])
                raise InputError(
                    f"Ground truth pair {first} names {side} vertex {int(values[first])}, but the "
                    f"{side} mesh has {n} vertices (0-based indices 0..{n - 1}){self._where()}. "
                    "Check that the ground truth belongs to these meshes."
                )
        return self


def identity_truth(n_source: int, n_target: int) -> GroundTruth:
    """Vertex i corresponds to vertex i (same connectivity).

    Raises
    ------
    ParameterError
        If the vertex counts differ: the identity cannot be the truth then.
    """
    if n_source != n_target:
        raise InputError(
            f"The identity ground truth needs meshes with equal vertex counts; the source has "
            f"{n_source} and the target {n_target}. Give a .vts pair or a file of vertex pairs."
        )
    index = np.arange(n_source, dtype=np.int64)
    return GroundTruth(index, index, "identity")


def _read_lines(path: Path, kind: str = "ground-truth") -> list[tuple[int, str]]:
    lines = read_index_lines(path, kind)
    if not lines:
        raise InputError(f"{path}: the {kind} file is empty.")
    return lines


def read_vts_lines(path, kind: str = "ground-truth") -> tuple[np.ndarray, np.ndarray]:
    """A ``.vts`` file's indices made 0-based as they stand (unchecked), and each one's line number, 1-based.

    For messages that name a line (:func:`read_vts` checks the range); ``kind`` names the file's
    use in them ("ground-truth", "landmark").
    """
    path = Path(path)
    values, numbers = [], []
    for number, line in _read_lines(path, kind):
        if not re.fullmatch(r"[+-]?\d{1,18}", line):  # 18 digits: always an int64
            raise InputError(f"{path}, line {number}: a .vts file holds one integer per line; "
                             f"got {line[:40]!r}.")
        values.append(int(line))
        numbers.append(number)
    return np.array(values, dtype=np.int64) - 1, np.array(numbers, dtype=np.int64)


def read_vts(path, n_vertices: int | None = None) -> np.ndarray:
    """Read a TOSCA ``.vts`` file (one **1-based** vertex index per line).

    Parameters
    ----------
    path : str or os.PathLike
    n_vertices : int, optional
        Vertex count of the mesh it indexes; indices above it raise.

    Returns
    -------
    vertices : (p,) int64
        0-based vertex indices (the file's values minus one).

    Raises
    ------
    ParameterError
        Missing or empty file, a line that is not one integer, an index < 1
        (the file is then probably 0-based) or > ``n_vertices``.
    """
    path = Path(path)
    vts = read_vts_lines(path)[0] + 1
    if vts.min() < 1:
        raise InputError(
            f"{path} holds index {int(vts.min())}, but .vts indices are 1-based (>= 1). "
            "If the file is 0-based, pass it as a file of vertex pairs instead."
        )
    if n_vertices is not None and vts.max() > n_vertices:
        raise InputError(
            f"{path} holds index {int(vts.max())} (1-based), but its mesh has {n_vertices} "
            "vertices. Check that the .vts file belongs to this mesh."
        )
    return vts - 1


def read_pairs(path, n_source: int | None = None) -> GroundTruth:
    """Read a file of 0-based vertex pairs, or a dense map with one index per line.

    Parameters
    ----------
    path : str or os.PathLike
        Lines ``i j`` (or ``i,j`` / ``i:j``); or lines holding one index each,
        line i being the target vertex of source vertex i (negative entries
        are skipped: unmapped).
    n_source : int, optional
        Vertex count of the source mesh: a dense map (one index per line) must
        then have exactly that many lines.

    Returns
    -------
    truth : GroundTruth

    Raises
    ------
    ParameterError
        Missing or empty file, a line that is not one or two integers, a
        mix of one- and two-column lines, a dense map whose line count is
        not ``n_source``, or a source vertex on two lines of pairs.
    """
    path = Path(path)
    rows = []
    for number, line in _read_lines(path):
        values = index_fields(line)
        if values is None or not 1 <= len(values) <= 2:
            raise InputError(f"{path}, line {number}: expected a 0-based vertex pair 'i j' "
                             f"(or one index per line); got {line[:40]!r}.")
        rows.append((number, values))
    widths = {len(values) for _, values in rows}
    if len(widths) > 1:
        odd = next(number for number, values in rows if len(values) != len(rows[0][1]))
        raise InputError(f"{path}, line {odd}: mixes one- and two-column lines; use one index "
                         "per line (a dense map) or one pair 'i j' per line throughout.")
    table = np.array([values for _, values in rows], dtype=np.int64)
    if table.shape[1] == 1:
        if n_source is not None and len(table) != n_source:
            raise InputError(
                f"{path} has {len(table)} lines of one index each (a dense map), but the source mesh "
                f"has {n_source} vertices: a dense map needs exactly one line per source vertex "
                f"({n_source} lines, -1 where a vertex has no truth). Check that the file belongs "
                "to this SOURCE, or give the known pairs as lines 'i j' (source, target) instead."
            )
        target = table[:, 0]
        source = np.flatnonzero(target >= 0)
        return GroundTruth(source, target[source], str(path))
    _refuse_repeated_sources(path, table, [number for number, _ in rows])
    return GroundTruth(table[:, 0], table[:, 1], str(path))


def _refuse_repeated_sources(path: Path, table: np.ndarray, numbers: list[int]) -> None:
    """A file of pairs names each source vertex once: a second line for one counted it twice (it
    scored 501 points on a 500-vertex source), and a second target contradicts the first."""
    first: dict[int, int] = {}
    for row, (source, target) in enumerate(table.tolist()):
        if source not in first:
            first[source] = row
            continue
        earlier = first[source]
        if table[earlier, 1] == target:
            raise InputError(f"{path}, line {numbers[row]}: the pair '{source} {target}' is also on line "
                             f"{numbers[earlier]}; give each pair once.")
        raise InputError(f"{path}, line {numbers[row]}: source vertex {source} already has the true target "
                         f"{int(table[earlier, 1])} on line {numbers[earlier]}, and here {target}; give each source "
                         "vertex one true target vertex.")


def load_ground_truth(spec: str | os.PathLike | Sequence[str | os.PathLike], *, n_source: int,
                      n_target: int) -> GroundTruth:
    """Load a ground truth from ``"identity"``, a ``.vts`` pair or a file of 0-based pairs.

    Parameters
    ----------
    spec : str, path, or a sequence of one or two of them
        ``"identity"``; ``(source.vts, target.vts)``; or one file of vertex
        pairs (see the module docstring).
    n_source, n_target : int
        Vertex counts of the meshes, to check every index.

    Returns
    -------
    truth : GroundTruth
        Checked against both vertex counts.

    Raises
    ------
    ParameterError
        A missing or malformed file, ``.vts`` files of different lengths,
        an index outside its mesh, or a spec of the wrong shape.
    """
    items = [spec] if isinstance(spec, (str, os.PathLike)) else list(spec)
    if len(items) == 1 and str(items[0]) == "identity":
        return identity_truth(n_source, n_target)
    if len(items) == 2:
        paths = [Path(item) for item in items]
        if not all(p.suffix.lower() == ".vts" for p in paths):
            raise InputError(
                "Two ground-truth files must both be .vts files (source, then target); got "
                f"{items[0]} and {items[1]}. A file of vertex pairs is given alone."
            )
        vts_source = read_vts(paths[0], n_source)
        vts_target = read_vts(paths[1], n_target)
        if vts_source.size != vts_target.size:
            raise InputError(
                f"The .vts files must have one line per template sample each; {paths[0]} has "
                f"{vts_source.size} lines and {paths[1]} has {vts_target.size}. "
                "Check that both come from the same dataset."
            )
        return GroundTruth(vts_source, vts_target, f"{paths[0].name} + {paths[1].name}")
    if len(items) == 1:
        path = Path(items[0])
        if path.suffix.lower() == ".vts":
            raise InputError(
                f"A .vts file ({path}) indexes one mesh only: give the source's and the "
                "target's .vts files together (e.g. --gt A.vts B.vts)."
            )
        return read_pairs(path, n_source).check(n_source, n_target)
    raise InputError(
        "A ground truth is 'identity', two .vts files or one file of vertex pairs; "
        f"got {len(items)} items."
    )
