"""Anchor selection and proximity-aided matching (ALGORITHM.md steps 6-7).

With the aligned embeddings, :math:`Z_{ij} = \\lVert X_i - Y_j \\rVert`. The
first anchor pair is :math:`\\arg\\min Z`; before each further one, ``Z`` is
lowered by half the geodesic distances to the previous anchors on both
meshes, :math:`Z_{ij} \\leftarrow Z_{ij} - \\tfrac12[g_1(i, a_l) + g_2(j, b_l)]`,
so the anchors spread over the shapes (a vertex already used by an anchor is
not used again). The final map is

.. math::

    C(i) = \\arg\\min_j \\lVert X_i - Y_j \\rVert
           + \\sum_{l=1}^{h} \\alpha_l \\, |g_1(i, a_l) - g_2(j, b_l)|

where :math:`g_1, g_2` are the geodesic distances of each mesh, normalised
so both meshes are on the same scale (the caller decides how; the pipeline
divides by each mesh's largest geodesic distance). With ``bijective=True``
and equal vertex counts the argmin becomes a linear assignment
(``scipy.optimize.linear_sum_assignment``).

Everything is computed in row blocks, so memory stays at ``block x n2``
except for the bijective option, which needs the whole cost matrix.
"""

from __future__ import annotations

from typing import Callable

import numpy as np
from scipy.optimize import linear_sum_assignment
from scipy.spatial.distance import cdist

from .errors import ParameterError

RowsFn = Callable[[int], np.ndarray]

_BLOCK_ELEMENTS = 4_000_000  # ~32 MB of float64 per block


def _blocks(n1: int, n2: int):
    step = max(1, _BLOCK_ELEMENTS // max(1, n2))
    for start in range(0, n1, step):
        yield slice(start, min(n1, start + step))


def select_anchors(X: np.ndarray, Y: np.ndarray, source_geodesics: RowsFn, target_geodesics: RowsFn,
                   n_anchors: int = 3) -> np.ndarray:
    """Choose spread-out, well-matched anchor pairs.

    Parameters
    ----------
    X : (n1, d) float
        Source embedding.
    Y : (n2, d) float
        Aligned target embedding.
    source_geodesics, target_geodesics : callable
        ``f(i)`` returns the normalised geodesic distances from vertex i to
        every vertex of that mesh, ``(n,)``.
    n_anchors : int
        h, the number of anchor pairs.

    Returns
    -------
    anchors : (h, 2) int
        Rows ``(a_l, b_l)``: source vertex, target vertex.
    """
    n1, n2 = len(X), len(Y)
    p1, p2 = np.zeros(n1), np.zeros(n2)
    anchors = np.empty((n_anchors, 2), dtype=np.int64)
    for l in range(n_anchors):
        best, best_ij = np.inf, (0, 0)
        for rows in _blocks(n1, n2):
            Z = cdist(X[rows], Y)
            Z -= p1[rows, None]
            Z -= p2[None, :]
            # A pair reusing an earlier anchor vertex adds nothing: exclude it.
            Z[np.isin(np.arange(rows.start, rows.stop), anchors[:l, 0]), :] = np.inf
            Z[:, anchors[:l, 1]] = np.inf
            flat = int(np.argmin(Z))
            if Z.flat[flat] < best:
                best = float(Z.flat[flat])
                best_ij = (rows.start + flat // n2, flat % n2)
        anchors[l] = best_ij
        p1 += 0.5 * source_geodesics(best_ij[0])
        p2 += 0.5 * target_geodesics(best_ij[1])
    return anchors


def anchor_descriptors(anchors_on_mesh: np.ndarray, geodesics: RowsFn, weights: np.ndarray) -> np.ndarray:
    """Weighted geodesic distances to each anchor, ``(n, h)``: column l is ``alpha_l g(., a_l)``."""
    if len(anchors_on_mesh) == 0:
        return np.zeros((0, 0))
    return np.stack([w * geodesics(int(a)) for a, w in zip(anchors_on_mesh, weights)], axis=1)


def _cost_block(X, Y, F1, F2, rows) -> np.ndarray:
    Z = cdist(X[rows], Y)
    if F1.size:
        Z += cdist(F1[rows], F2, metric="cityblock")
    return Z


def proximity_matching(X: np.ndarray, Y: np.ndarray, F1: np.ndarray, F2: np.ndarray,
                       *, bijective: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """Final map from the embedding distance plus the anchor term.

    Parameters
    ----------
    X : (n1, d) float
        Source embedding.
    Y : (n2, d) float
        Aligned target embedding.
    F1 : (n1, h) float
        :func:`anchor_descriptors` of the source (may be empty).
    F2 : (n2, h) float
        :func:`anchor_descriptors` of the target.
    bijective : bool
        Solve a linear assignment instead of a row-wise argmin; needs
        ``n1 == n2``.

    Returns
    -------
    mapping : (n1,) int
        ``mapping[i]`` is the target vertex matched to source vertex i.
    cost : (n1,) float
        The cost of each chosen pair.
    """
    n1, n2 = len(X), len(Y)
    if bijective:
        if n1 != n2:
            raise ParameterError(
                f"A bijective map needs meshes with the same number of vertices; the source has {n1} "
                f"and the target {n2}. Drop --bijective (bijective=False) or remesh one of them."
            )
        C = _cost_block(X, Y, F1, F2, slice(0, n1))
        rows, cols = linear_sum_assignment(C)
        mapping = np.empty(n1, dtype=np.int64)
        mapping[rows] = cols
        return mapping, C[np.arange(n1), mapping]
    mapping = np.empty(n1, dtype=np.int64)
    cost = np.empty(n1)
    for rows in _blocks(n1, n2):
        C = _cost_block(X, Y, F1, F2, rows)
        j = np.argmin(C, axis=1)
        mapping[rows] = j
        cost[rows] = C[np.arange(len(j)), j]
    return mapping, cost
