"""The one-to-one map nearest to a vertex map (``bijective=True``).

The pipeline's one-to-one maps come from a linear assignment (steps 7 and
the refinement's last step), but some maps it may return are not one-to-one:
an unrefined start of the whole-map choice (distances to matched tips or to
the user's landmarks, :mod:`meshcorr.stages.landmarks`) and any map once the
user's landmarks are pinned into it. :func:`nearest_bijection` turns such a
map into the permutation whose images are nearest to the map's, in the
squared Euclidean distance on the target,

.. math::

    \\pi^* = \\arg\\min_{\\pi \\in S_n} \\sum_i \\lVert y_{T(i)} - y_{\\pi(i)} \\rVert^2 ,

with the fixed pairs (the landmarks) held: their rows and columns leave the
problem before it is solved. The assignment is
``scipy.optimize.linear_sum_assignment``; only the cost is built here. A map
that is already one-to-one and holds the fixed pairs is returned as it is.
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import linear_sum_assignment

from ..errors import ParameterError


def nearest_bijection(mapping: np.ndarray, target_vertices: np.ndarray, *,
                      fixed: np.ndarray | None = None) -> np.ndarray:
    """The permutation nearest to ``mapping`` on the target (module docstring).

    Parameters
    ----------
    mapping : (n,) int
        ``mapping[i]``: target vertex of source vertex i; the target has n
        vertices too.
    target_vertices : (n, 3) float
        The target's vertex positions.
    fixed : (L, 2) int, optional
        (source, target) pairs the result must hold, distinct on both sides.

    Returns
    -------
    permutation : (n,) int
        Every target vertex exactly once; ``permutation[a] == b`` for each
        fixed pair (a, b).

    Raises
    ------
    ParameterError
        If the counts differ, or two fixed pairs share a source or a target vertex.
    """
    mapping = np.asarray(mapping, dtype=np.int64)
    points = np.asarray(target_vertices, dtype=np.float64)
    n = len(mapping)
    if points.shape != (n, 3):
        raise ParameterError(f"A one-to-one map needs as many target vertices as source vertices; "
                             f"got {n} and {len(points)}.")
    fixed = check_fixed_pairs(fixed)
    if len(np.unique(mapping)) == n and np.array_equal(mapping[fixed[:, 0]], fixed[:, 1]):
        return mapping.copy()
    result = np.empty(n, dtype=np.int64)
    result[fixed[:, 0]] = fixed[:, 1]
    rows = np.setdiff1d(np.arange(n), fixed[:, 0])
    columns = np.setdiff1d(np.arange(n), fixed[:, 1])
    images = points[mapping[rows]]
    cost = (np.einsum("ij,ij->i", images, images)[:, None] - 2.0 * images @ points[columns].T
            + np.einsum("ij,ij->i", points[columns], points[columns])[None, :])
    chosen_rows, chosen_columns = linear_sum_assignment(cost)
    result[rows[chosen_rows]] = columns[chosen_columns]
    return result


def check_fixed_pairs(fixed: np.ndarray | None) -> np.ndarray:
    """``fixed`` as an ``(L, 2)`` int array, checked to name each source and each target vertex once.

    Raises
    ------
    ParameterError
        If two pairs share a source or a target vertex: no one-to-one map holds both.
    """
    fixed = np.zeros((0, 2), dtype=np.int64) if fixed is None else np.asarray(fixed, dtype=np.int64).reshape(-1, 2)
    for side, name in ((0, "source"), (1, "target")):
        values, counts = np.unique(fixed[:, side], return_counts=True)
        if (counts > 1).any():
            raise ParameterError(f"A one-to-one map (bijective) cannot send two landmarks to one place: {name} "
                                 f"vertex {int(values[counts > 1][0])} is in {int(counts.max())} landmark pairs. "
                                 "Give each vertex once, or drop --bijective.")
    return fixed
