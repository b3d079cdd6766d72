"""Anchor selection and proximity-aided matching (docs/method.md, steps 6-7).

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

Small problems (``n1 * n2 <= EXACT_PAIRS``) are computed in row blocks, so
memory stays at ``block x n2``. Larger ones never form ``n1 x n2`` blocks:

- :func:`proximity_matching` is **approximate**: each row takes the
  cheapest of its ``N_CANDIDATES`` nearest target points in the embedding
  and its ``N_CANDIDATES // 2`` nearest in the combined space
  :math:`(Y_j, F_j)` (KD-trees; the second catches matches the anchor
  term prefers over the embedding's nearest). Measured on the 115k-vertex
  Sumner cat pair (5000 sampled rows): costs 0.26 % above the best of a
  candidate pool four times larger; on TOSCA 5k pairs 96-100 % of the rows
  equal the dense argmin, with the same mean error. Without anchor terms
  it is exact.
- :func:`select_anchors` is **approximate**: pairs are restricted to each
  source vertex's ``N_CANDIDATES`` nearest target vertices in the embedding
  (the first anchor, the closest pair, is still exact; later ones may miss
  a pair whose embedding distance is not among a vertex's nearest).

The bijective option always needs the whole cost matrix.
"""

from __future__ import annotations

from typing import Callable

import numpy as np
from scipy.optimize import linear_sum_assignment
from scipy.spatial import cKDTree
from scipy.spatial.distance import cdist

from ..runtime.threads import kdtree_query
from ..errors import ParameterError
from .tps import mean_pairwise_distance

RowsFn = Callable[[int], np.ndarray]

_BLOCK_ELEMENTS = 4_000_000  # ~32 MB of float64 per block

#: Largest ``n1 * n2`` matched by the exact dense (row block) computation.
EXACT_PAIRS = 4_000_000
#: Length scales of the anchor term: the embedding's (:func:`embedding_spread`) or the paper's geodesic one.
ANCHOR_SCALES = ("embedding", "geodesic")

#: h and alpha: anchor pairs of the matching and the weight of each one's geodesic term (the defaults of
#: :class:`meshcorr.Settings`).
N_ANCHORS, ANCHOR_WEIGHT = 3, 1.0
#: Target candidates per source vertex in anchor selection beyond ``EXACT_PAIRS``.
N_CANDIDATES = 16
#: Distances and indices of nearest neighbours, ``(n1, k)`` each (:func:`embedding_neighbours`).
Neighbours = tuple[np.ndarray, np.ndarray]


def _blocks(n1: int, n2: int):
    step = max(1, _BLOCK_ELEMENTS // max(1, n2))
    for start in range(0, n1, step):
        yield slice(start, min(n1, start + step))


def select_anchors(X: np.ndarray, Y: np.ndarray, source_geodesics: RowsFn, target_geodesics: RowsFn,
                   n_anchors: int = N_ANCHORS, *, neighbours: Neighbours | None = None) -> np.ndarray:
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
    neighbours : tuple of (n1, k) arrays, optional
        :func:`embedding_neighbours` of ``X`` in ``Y`` if already computed
        (used beyond ``EXACT_PAIRS`` pairs only).

    Returns
    -------
    anchors : (h, 2) int
        Rows ``(a_l, b_l)``: source vertex, target vertex. Beyond
        ``EXACT_PAIRS`` pairs, chosen among each source vertex's
        ``N_CANDIDATES`` nearest target vertices (see the module docstring).
    """
    n1, n2 = len(X), len(Y)
    if n1 * n2 > EXACT_PAIRS:
        return _select_anchors_candidates(X, Y, source_geodesics, target_geodesics, n_anchors,
                                          neighbours if neighbours is not None else embedding_neighbours(X, Y))
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


def _select_anchors_candidates(X, Y, source_geodesics: RowsFn, target_geodesics: RowsFn,
                               n_anchors: int, neighbours: Neighbours) -> np.ndarray:
    """:func:`select_anchors` over each source vertex's nearest target vertices only."""
    n1 = len(X)
    Z, J = neighbours
    p1, p2 = np.zeros(n1), np.zeros(len(Y))
    used1, used2 = np.zeros(n1, dtype=bool), np.zeros(len(Y), dtype=bool)
    anchors = np.empty((n_anchors, 2), dtype=np.int64)
    for l in range(n_anchors):
        value = Z - p1[:, None] - p2[J]
        value[used1] = np.inf
        value[used2[J]] = np.inf
        flat = int(np.argmin(value))
        a, b = flat // J.shape[1], int(J.flat[flat])
        anchors[l] = a, b
        used1[a] = used2[b] = True
        p1 += 0.5 * source_geodesics(a)
        p2 += 0.5 * target_geodesics(b)
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
                       *, bijective: bool = False, neighbours: Neighbours | None = None
                       ) -> tuple[np.ndarray, np.ndarray]:
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
    if n1 * n2 > EXACT_PAIRS:
        return _candidate_matching(X, Y, F1, F2, neighbours if neighbours is not None else embedding_neighbours(X, Y))
    mapping = np.empty(n1, dtype=np.int64)
    cost = np.empty(n1)
    for rows in _blocks(n1, n2):
        C = _cost_block(X, Y, F1, F2, rows)
        j = np.argmin(C, axis=1)
        mapping[rows] = j
        cost[rows] = C[np.arange(len(j)), j]
    return mapping, cost


def embedding_neighbours(X: np.ndarray, Y: np.ndarray, k: int = N_CANDIDATES) -> Neighbours:
    """The ``k`` nearest rows of ``Y`` to each row of ``X`` (KD-tree).

    Parameters
    ----------
    X : (n1, d) float
    Y : (n2, d) float
    k : int
        Clipped to ``n2``.

    Returns
    -------
    distances, indices : (n1, min(k, n2)) float and int
        Both :func:`select_anchors` and :func:`proximity_matching` need this
        query beyond ``EXACT_PAIRS`` pairs (~1 s at 115k vertices): compute it
        once and pass it to both as ``neighbours``.
    """
    k = min(int(k), len(Y))
    Z, J = kdtree_query(cKDTree(Y), X, k=k)
    return Z.reshape(len(X), k), J.reshape(len(X), k)


def _candidate_matching(X, Y, F1, F2, neighbours: Neighbours) -> tuple[np.ndarray, np.ndarray]:
    """Row-wise argmin of the matching cost over KD-tree candidates, without ``n1 x n2`` blocks.

    Candidates of source vertex i: its ``k`` nearest target points in the
    embedding (exact search) and its ``k // 2`` nearest in the combined
    space ``[Y_j, F2_j]`` (approximate search, ``eps=3``: on dense meshes the
    exact search is 4x slower there, as the two shapes' anchor distances
    differ by more than the vertex spacing). The row takes the candidate of
    lowest exact cost; ties go to the lower target index, as in the dense
    path. Without anchor terms the result is the exact argmin.
    """
    n1, n2 = len(X), len(Y)
    nearest = neighbours[1]
    k = nearest.shape[1]
    combined = None
    if F1.size:
        combined = (cKDTree(np.hstack([Y, F2])), np.hstack([X, F1]), max(1, k // 2))
    width = k + (combined[2] if combined else 0)
    mapping = np.empty(n1, dtype=np.int64)
    cost = np.empty(n1)
    step = max(1, _BLOCK_ELEMENTS // (8 * width))
    for start in range(0, n1, step):
        rows = np.arange(start, min(n1, start + step))
        J = nearest[rows]
        if combined is not None:
            tree, points, kk = combined
            J = np.hstack([J, kdtree_query(tree, points[rows], k=kk, eps=3.0)[1].reshape(len(rows), kk)])
        C = _pair_cost(X, Y, F1, F2, np.repeat(rows, width), J.ravel()).reshape(len(rows), width)
        cost[rows] = C.min(axis=1)
        mapping[rows] = np.where(C == cost[rows, None], J, n2).min(axis=1)  # ties: lowest index
    return mapping, cost


def _pair_cost(X, Y, F1, F2, i: np.ndarray, j: np.ndarray) -> np.ndarray:
    """Matching cost of the pairs ``(i[t], j[t])``, ``(len(i),)``."""
    c = np.linalg.norm(X[i] - Y[j], axis=1)
    if F1.size:
        c += np.abs(F1[i] - F2[j]).sum(axis=1)
    return c


def embedding_spread(spectrum) -> float:
    """The anchors' length scale: :func:`meshcorr.stages.tps.mean_pairwise_distance` of a spectrum's embedding.

    The anchor term of the proximity-aided matching is put in the embedding's
    length scale with it (docs/method.md, step 6). It depends on the source
    shape only (a seeded sample of its embedding), so it is computed once per
    spectrum and kept in ``spectrum.memo["spread"]``: a prepared shape
    matched many times measures it once (the same value).
    """
    if "spread" not in spectrum.memo:
        spectrum.memo["spread"] = mean_pairwise_distance(spectrum.embedding)
    return spectrum.memo["spread"]


def match_with_anchors(X: np.ndarray, warped: np.ndarray, source_geodesics: RowsFn, target_geodesics: RowsFn,
                       spread: float, *, n_anchors: int, anchor_weight: float, anchor_scale: str,
                       bijective: bool) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Step 6 (and 7): anchors, then proximity-aided matching of an aligned embedding.

    Parameters
    ----------
    X : (n1, d) float
        The source embedding.
    warped : (n2, d) float
        The target embedding after alignment (TPS-ICP).
    source_geodesics, target_geodesics : callable
        ``rows(i) -> (n,)`` normalised geodesic distances from vertex ``i``.
    spread : float
        The mean distance between embedded source points,
        :func:`embedding_spread` (used with ``anchor_scale="embedding"``).
    n_anchors, anchor_weight, anchor_scale, bijective
        h, alpha, the length scale of the anchor term and the one-to-one
        matching (:class:`meshcorr.Settings`).

    Returns
    -------
    mapping : (n1,) int
        The target vertex of each source vertex, minimising
        :math:`\\lVert X_i - Y_j \\rVert + \\alpha' \\sum_l |g_S(i, a_l) - g_T(j, b_l)|`.
    cost : (n1,) float
        Each source vertex's matching cost.
    anchors : (h, 2) int
        The anchor pairs ``(a_l, b_l)``.

    Notes
    -----
    With ``anchor_scale="embedding"`` the normalised geodesic term is put
    in the embedding's length scale: :math:`\\alpha' = \\alpha \\, s / (h \\bar g)`
    with :math:`s` = ``spread`` and :math:`\\bar g` the mean normalised
    geodesic distance to the anchors (docs/method.md, "Choices where the
    paper is silent": geodesics in [0, 1] summed over three anchors dwarf
    embedding distances of ~0.1-0.3).
    """
    # Beyond EXACT_PAIRS both steps search each source point's nearest embedded target points.
    neighbours = embedding_neighbours(X, warped) if len(X) * len(warped) > EXACT_PAIRS else None
    anchors = select_anchors(X, warped, source_geodesics, target_geodesics, n_anchors, neighbours=neighbours)
    F1 = anchor_descriptors(anchors[:, 0], source_geodesics, np.ones(n_anchors))
    F2 = anchor_descriptors(anchors[:, 1], target_geodesics, np.ones(n_anchors))
    scale = anchor_weight
    if anchor_scale == "embedding" and n_anchors > 0:
        mean_geodesic = 0.5 * (F1.mean() + F2.mean())
        scale *= spread / (n_anchors * max(mean_geodesic, 1e-12))
    mapping, cost = proximity_matching(X, warped, F1 * scale, F2 * scale, bijective=bijective,
                                       neighbours=neighbours)
    return mapping, cost, anchors
