"""A dense map from a few corresponding vertices, and the checking of user landmarks.

Given pairs :math:`(a_l, b_l)`, each vertex is described by its geodesic
distances to the landmarks of its own shape, scaled by their mean (so that a
uniform change of size, or of proportion averaged over the shape, cancels):

.. math::

    F_1(i) = \\frac{(g_1(a_1, i), \\dots, g_1(a_L, i))}{\\operatorname{mean} g_1(a, \\cdot)},
    \\qquad
    F_2(j) = \\frac{(g_2(b_1, j), \\dots, g_2(b_L, j))}{\\operatorname{mean} g_2(b, \\cdot)},

and source vertex i goes to the target vertex of nearest :math:`F_2` (a
KD-tree query). These are the geodesic "anchor" descriptors of the paper's
step 6 without the embedding term, and the landmark-distance descriptors of
functional-map pipelines (Ovsjanikov et al., "Functional maps", SIGGRAPH
2012, section 6). The map is coarse (it is only as fine as the landmarks'
spread) and is meant to be refined (:mod:`meshcorr.stages.refine`).
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Callable

import numpy as np
from scipy.spatial import cKDTree

from ..errors import InputError, LandmarkError, ParameterError
from ..io.indices import index_fields, read_index_lines
from ..core.mesh import Mesh

RowFn = Callable[[int], np.ndarray]


def landmark_descriptors(geodesics_from: RowFn, landmarks: np.ndarray) -> np.ndarray:
    """``(n, L)`` geodesic distances to the landmarks, divided by their mean."""
    rows = np.array([np.asarray(geodesics_from(int(v)), dtype=np.float64) for v in landmarks]).T
    return rows / max(float(rows.mean()), 1e-12)


def landmark_map(source_geodesics: RowFn, target_geodesics: RowFn, pairs: np.ndarray) -> np.ndarray:
    """Dense source -> target vertex map from landmark pairs (module docstring).

    Parameters
    ----------
    source_geodesics, target_geodesics : callable
        ``f(i)`` returns the geodesic distances from vertex i on that shape, ``(n,)``.
    pairs : (L, 2) int
        (source vertex, target vertex), local numbering, L >= 1.

    Returns
    -------
    mapping : (n1,) int
        Landmark source vertices go exactly to their target vertex.
    """
    pairs = np.asarray(pairs, dtype=np.int64)
    F1 = landmark_descriptors(source_geodesics, pairs[:, 0])
    F2 = landmark_descriptors(target_geodesics, pairs[:, 1])
    mapping = cKDTree(F2).query(F1)[1].astype(np.int64)
    mapping[pairs[:, 0]] = pairs[:, 1]
    return mapping


def landmark_disagreement(source_geodesics: RowFn, target_geodesics: RowFn, pairs: np.ndarray) -> np.ndarray:
    """How much each landmark pair's geodesic distances to the other landmarks differ across the shapes.

    For a near-isometric pair, :math:`g_1(a_l, a_m) \\approx s\\, g_2(b_l, b_m)` for every two
    pairs, :math:`s` the ratio of sizes (the median over the pairs of their median ratio, so that a
    few wrong pairs do not set it). Pair l's disagreement is the median over the other pairs m of
    :math:`|g_1(a_l, a_m) - s\\, g_2(b_l, b_m)|`, divided by the mean distance between the source
    landmarks: a pair whose target vertex is not its source vertex's partner disagrees with nearly all the others;
    a right pair only with the few wrong ones, which the median sets aside (with fewer than half of
    the pairs wrong).

    Parameters
    ----------
    source_geodesics, target_geodesics : callable
        ``f(i)`` returns the geodesic distances from vertex i on that shape, ``(n,)``.
    pairs : (L, 2) int
        (source vertex, target vertex), local numbering.

    Returns
    -------
    disagreement : (L,) float
        Zeros with fewer than 3 pairs (two distances agree after scaling, whatever they are).
    """
    pairs = np.asarray(pairs, dtype=np.int64)
    count = len(pairs)
    if count < 3:
        return np.zeros(count)
    d1 = np.array([np.asarray(source_geodesics(int(a)), dtype=np.float64)[pairs[:, 0]] for a in pairs[:, 0]])
    d2 = np.array([np.asarray(target_geodesics(int(b)), dtype=np.float64)[pairs[:, 1]] for b in pairs[:, 1]])
    d1, d2 = (d1 + d1.T) / 2, (d2 + d2.T) / 2  # exact geodesics are symmetric; approximate ones nearly
    off = ~np.eye(count, dtype=bool)
    # The size ratio: the median of the pairs' own medians (with 2 wrong pairs of 7, 11 of the 21
    # distances involve one, but 5 of the 7 rows' medians are right).
    ratio = np.where(off & (d2 > 0), d1 / np.where(d2 > 0, d2, 1.0), np.nan)
    rows = np.nanmedian(ratio, axis=1) if np.isfinite(ratio).any(axis=1).all() else np.ones(count)
    scale = float(np.median(rows))
    gap = np.where(off, np.abs(d1 - scale * d2), np.nan)
    return np.nanmedian(gap, axis=1) / max(float(d1[off].mean()), 1e-12)


def landmark_table(landmarks) -> np.ndarray | None:
    """User landmark pairs as a table of vertex indices, checked without the meshes.

    Parameters
    ----------
    landmarks : None or sequence of (source_index, target_index)

    Returns
    -------
    table : (L, 2) int64 or None
        None when ``landmarks`` is None or empty.

    Raises
    ------
    ParameterError
        Not a table of pairs, or indices that are not whole numbers.
    """
    if landmarks is None:
        return None
    try:
        table = np.asarray(landmarks)
    except (TypeError, ValueError):
        table = np.asarray(None)
    if table.size == 0:
        return None
    if table.ndim != 2 or table.shape[1] != 2:
        raise ParameterError("The 'landmarks' parameter must be (source vertex, target vertex) integer "
                             f"pairs, e.g. [(0, 12), (5, 40)]. Got an array of shape {table.shape} "
                             f"and dtype {table.dtype} instead.")
    whole = table.dtype.kind in "iu" or (table.dtype.kind == "f" and bool(np.all(np.isfinite(table)))
                                         and bool(np.all(table == np.round(table))))
    if whole and _has_bool(landmarks):  # numpy took (True, 3) for (1, 3)
        raise ParameterError("Landmark indices must be whole numbers (0-based vertex indices), not True or "
                             f"False; got {list(landmarks)[:4]}.")
    if not whole:
        raise ParameterError("Landmark indices must be whole numbers (0-based vertex indices); got "
                             f"{table.reshape(-1)[:4].tolist()}...")
    return table.astype(np.int64)


def _has_bool(landmarks) -> bool:
    """Whether a sequence of pairs (not an array: numpy's bool arrays are no whole numbers) holds a bool."""
    if isinstance(landmarks, np.ndarray):
        return False
    try:
        return any(isinstance(value, (bool, np.bool_)) for pair in landmarks for value in pair)
    except TypeError:
        return False


def check_landmarks(landmarks, source: Mesh, target: Mesh) -> np.ndarray | None:
    """Validate user landmark pairs and put them in the meshes' local numbering.

    Parameters
    ----------
    landmarks : None or sequence of (source_index, target_index)
        0-based indices into the input meshes' vertex lists.
    source, target : Mesh
        As loaded (vertices may have been dropped by ``largest_component``).

    Returns
    -------
    pairs : (L, 2) int64 or None
        Local vertex numbers of each pair; None when ``landmarks`` is None or empty.

    Raises
    ------
    ParameterError
        Not pairs of whole numbers (:func:`landmark_table`).
    LandmarkError
        An index out of range, a source vertex given two different targets,
        or a vertex that was removed with a dropped component (a pair given
        twice is kept once).
    """
    table = landmark_table(landmarks)
    if table is None:
        return None
    for column, mesh, side in ((0, source, "source"), (1, target, "target")):
        bad = (table[:, column] < 0) | (table[:, column] >= mesh.n_input)  # not on a hole's cap
        if bad.any():
            row = int(np.flatnonzero(bad)[0])
            raise LandmarkError(f"Landmark {row} has {side} index {int(table[row, column])}, outside the "
                                f"{side} mesh's vertices [0, {mesh.n_input}). Indices are 0-based.",
                                row=row, column=column, problem="range", limit=mesh.n_input)
    # The same pair given twice says nothing new (a .vts pair may list a point twice); a source
    # vertex sent to two different targets is a contradiction. Rows keep their given numbers.
    rows = np.sort(np.unique(table, axis=0, return_index=True)[1])
    sources, counts = np.unique(table[rows, 0], return_counts=True)
    if (counts > 1).any():
        given = np.flatnonzero(table[:, 0] == sources[counts > 1][0])
        first, row = int(given[0]), int(given[table[given, 1] != table[given[0], 1]][0])
        raise LandmarkError(f"Source vertex {int(table[row, 0])} has more than one landmark (pairs {first} and "
                            f"{row}: target vertices {int(table[first, 1])} and {int(table[row, 1])}); give each "
                            "source vertex at most one target vertex.",
                            row=row, column=0, problem="repeat", first=first)
    local = []
    for column, mesh, side in ((0, source, "source"), (1, target, "target")):
        lookup = np.full(mesh.n_original, -1, dtype=np.int64)
        lookup[mesh.kept] = np.arange(mesh.n_vertices)
        mapped = lookup[table[rows, column]]
        if (mapped < 0).any():
            row = int(rows[np.flatnonzero(mapped < 0)[0]])
            raise LandmarkError(f"Landmark {row}: {side} vertex {int(table[row, column])} lies on a "
                                "component that was removed (largest_component=True); choose a vertex "
                                "on the largest component.", row=row, column=column, problem="removed")
        local.append(mapped)
    return np.stack(local, axis=1)


def read_landmarks(path: str | os.PathLike) -> np.ndarray:
    """Read a landmark file: one ``source_index target_index`` pair a line, 0-based.

    Blank lines and ``#`` comments are skipped; the two indices may be
    separated by spaces, a comma, a colon or a semicolon.

    Parameters
    ----------
    path : str or os.PathLike

    Returns
    -------
    pairs : (L, 2) int64

    Raises
    ------
    InputError
        A missing, non-text or empty file, or a line that is not two integers
        (named by its number).
    """
    return read_landmark_lines(path)[0]


def read_landmark_lines(path: str | os.PathLike) -> tuple[np.ndarray, np.ndarray]:
    """:func:`read_landmarks`, and the 1-based line number of each pair ``(L,)`` int (for messages)."""
    path = Path(path)
    pairs, numbers = [], []
    for number, line in read_index_lines(path, kind="landmark"):
        values = index_fields(line)
        if values is None or len(values) != 2:
            raise InputError(f"{path}, line {number}: expected a 0-based vertex pair 'source_index "
                             f"target_index'; got {line[:40]!r}.")
        pairs.append(values)
        numbers.append(number)
    if not pairs:
        raise InputError(f"{path}: the landmark file holds no pairs.")
    return np.array(pairs, dtype=np.int64), np.array(numbers, dtype=np.int64)
