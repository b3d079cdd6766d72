"""Exact nearest-neighbour search between two sets of rows (spectral coordinates, points).

The kernel of every step that turns coordinates back into a vertex map:
ZoomOut (:mod:`meshcorr.stages.refine`), functional maps
(:mod:`meshcorr.spectral.fmap`), smooth shells, the oriented start, partial
shapes. For each of ``n1`` query rows it returns the index of the nearest of
``n2`` point rows in the Euclidean norm,

.. math::

    T(i) = \\arg\\min_j \\lVert q_i - p_j \\rVert^2
         = \\arg\\min_j \\left( |p_j|^2 - 2 q_i \\cdot p_j \\right),

by brute force in row blocks (BLAS), which is faster than a KD-tree in the
20-60 dimensions of a spectral basis (``benchmarks/RESULTS-refine.md``).

Speed at 100k+ vertices (issue 5). Above :data:`PRUNE_ABOVE` points the
search is pruned exactly by the triangle inequality over seeded cells
(:func:`_nearest_rows_pruned`, in the spirit of cluster-pruning exact search,
e.g. Fukunaga & Narendra, "A branch and bound algorithm for computing
k-nearest neighbors", IEEE Trans. Computers 1975): the same map, ~15x less
work on spectral coordinates. Every brute-force search of more than
:data:`SCREEN_ABOVE` pairs is first done in single precision with a rigorous
error bound, and only its near-ties again in double precision
(:func:`nearest_rows`): the double-precision map, ~25 % less time at
5k x 5k x 40 (``benchmarks/RESULTS-collections.md``).
"""

from __future__ import annotations

import numpy as np

__all__ = ["PRUNE_ABOVE", "SCREEN_ABOVE", "nearest_rows", "nearest_vertices"]

#: Point count above which :func:`nearest_vertices` prunes by cells (:func:`_nearest_rows_pruned`, exact)
#: instead of brute force.
PRUNE_ABOVE = 20_000
#: Squared distances per block of :func:`nearest_rows` (8 MB of float64).
_NEAREST_BLOCK = 1 << 20
#: Single-precision squared distances per block of the screen of :func:`nearest_rows` (2 MB: blocks of
#: 2^18-2^21 entries took 0.066, 0.056, 0.060 and 0.076 s at 5k x 5k x 40 on one core).
_SCREEN_BLOCK = 1 << 19
#: Fewest ``len(queries) * len(points)`` for which :func:`nearest_rows` screens in single precision
#: first (below it the screen's second pass costs more than it saves).
SCREEN_ABOVE = 1 << 20
#: Unit roundoff of float32 and float64.
_U32, _U64 = 2.0 ** -24, 2.0 ** -53


def nearest_rows(queries: np.ndarray, points: np.ndarray) -> np.ndarray:
    """``(n1,)`` int: the index of the nearest row of ``points`` ``(n2, d)`` for each row of ``queries`` ``(n1, d)``.

    The double-precision answer :math:`\\arg\\min_j \\lVert q_i - p_j \\rVert`.

    Brute force in row blocks (BLAS), faster than a KD-tree in the 20-60
    dimensions of a spectral basis (``benchmarks/RESULTS-refine.md``). The
    answer is that of the double-precision search
    (:func:`_nearest_rows_double`), whose near-ties do not depend on the
    number of BLAS threads; single precision alone is 2x faster but was
    measured to resolve a near-tie differently with 1 and 2 threads. Above
    :data:`SCREEN_ABOVE` pairs the squared distances are first computed in
    single precision, with a rigorous bound on their error
    (:func:`_single_precision_bound`): a query whose best point beats the
    runner-up by more than twice the bound (plus the double-precision
    search's own bound) has that best point as its double-precision answer,
    provably; every other query (a near-tie, a few percent of them) is
    searched again in double precision. Same map as the double-precision
    search, with any number of threads.
    """
    queries, points = np.asarray(queries, dtype=np.float64), np.asarray(points, dtype=np.float64)
    if len(queries) * len(points) <= SCREEN_ABOVE or not (np.isfinite(queries).all() and np.isfinite(points).all()):
        return _nearest_rows_double(queries, points)
    augmented_points = _augmented_points(points)
    augmented_queries = np.hstack([queries, np.ones((len(queries), 1))])
    bound = _single_precision_bound(augmented_queries, augmented_points)
    points32 = augmented_points.astype(np.float32)
    queries32 = augmented_queries.astype(np.float32)
    out = np.empty(len(queries), dtype=np.int64)
    unsure = np.zeros(len(queries), dtype=bool)
    step = max(1, min(len(queries), _SCREEN_BLOCK // max(1, len(points))))
    buffer = np.empty((step, len(points)), dtype=np.float32)
    for start in range(0, len(queries), step):
        block = np.matmul(queries32[start:start + step], points32, out=buffer[:min(step, len(queries) - start)])
        rows = np.arange(len(block))
        best = np.argmin(block, axis=1)
        best_value = block[rows, best].astype(np.float64)
        block[rows, best] = np.inf
        runner_up = block.min(axis=1).astype(np.float64)
        out[start:start + len(block)] = best
        unsure[start:start + len(block)] = runner_up - best_value <= 2.0 * bound[start:start + len(block)]
    if unsure.any():
        out[unsure] = _nearest_rows_double(queries[unsure], points)
    return out


def _augmented_points(points: np.ndarray) -> np.ndarray:
    """``(K + 1, n)``: the columns ``[-2 p, |p|^2]``, so that ``[q, 1] . column = |q - p|^2 - |q|^2``."""
    return np.vstack([-2.0 * points.T, np.einsum("ij,ij->i", points, points)[None, :]])


def _single_precision_bound(augmented_queries: np.ndarray, augmented_points: np.ndarray) -> np.ndarray:
    r"""``(n1,)``: a bound on the error of each single-precision ``[q, 1] . [-2 p, |p|^2]``, plus the double one.

    Rounding the inputs to float32 changes each product term by at most
    :math:`(2u + u^2)|a_k b_k|`, and a dot product of :math:`n` terms in
    floating point (any summation order, FMA or not) is within
    :math:`\gamma_n \sum_k |a_k b_k|`, :math:`\gamma_n = nu / (1 - nu)`, of
    the exact one (Higham, "Accuracy and stability of numerical algorithms",
    2nd ed., section 3.1). Here :math:`\sum_k |a_k b_k| = 2 \sum_k |q_k||p_k|
    + |p|^2 \le 2 |q| P + P^2` (Cauchy-Schwarz), :math:`P` the largest point
    norm. The double-precision search's own :math:`\gamma_n` (with
    :math:`u = 2^{-53}`) is added, so that a screened answer is the one it
    would give; the whole is doubled for the rounding of this bound itself.
    """
    n = augmented_points.shape[0]
    gamma32, gamma64 = (n * u / (1.0 - n * u) for u in (_U32, _U64))
    largest = float(np.sqrt(augmented_points[-1].max()))  # the last row holds |p|^2
    norms = np.sqrt(np.einsum("ij,ij->i", augmented_queries[:, :-1], augmented_queries[:, :-1]))
    return 2.0 * (gamma32 + 2.0 * _U32 + _U32 ** 2 + gamma64) * (2.0 * norms * largest + largest ** 2)


def _nearest_rows_double(queries: np.ndarray, points: np.ndarray) -> np.ndarray:
    """:func:`nearest_rows` in double precision only (the reference answer)."""
    queries, points = np.asarray(queries, dtype=np.float64), np.asarray(points, dtype=np.float64)
    # |q - p|^2 - |q|^2 = [q, 1] . [-2 p, |p|^2]: one product per block, no separate pass adding |p|^2
    # (25 % faster at 5k x 5k x 40).
    augmented_points = _augmented_points(points)
    augmented_queries = np.hstack([queries, np.ones((len(queries), 1))])
    out = np.empty(len(queries), dtype=np.int64)
    step = max(1, min(len(queries), _NEAREST_BLOCK // max(1, len(points))))
    # One buffer for every block: fresh 30 MB temporaries per block cost as
    # much in page faults as the products themselves (measured at 5k).
    buffer = np.empty((step, len(points)))
    for start in range(0, len(queries), step):
        block = augmented_queries[start:start + step]
        out[start:start + step] = np.argmin(np.matmul(block, augmented_points, out=buffer[:len(block)]), axis=1)
    return out


def _nearest_rows_pruned(queries: np.ndarray, points: np.ndarray, *, n_cells: int = 2000,
                         random_state: int | None = 0) -> np.ndarray:
    """Exact nearest row of ``points`` for each query, by cells and the triangle inequality.

    ``n_cells`` seeded points are cell centres :math:`c`; every point joins
    the cell of its nearest centre, and :math:`r_c` is the cell's radius.
    Queries are grouped by their nearest centre. A query :math:`q` whose
    best distance so far is :math:`d` cannot have its nearest point in cell
    :math:`c` when :math:`\\lVert q - c \\rVert - r_c > d`; each group first
    searches its own cell, then brute-forces only the cells that bound
    leaves open. The answer equals brute force (up to ties) at a fraction of
    its ``O(n1 n2 K)`` cost when points lie on a low-dimensional manifold,
    as spectral coordinates of a surface do.
    """
    n2 = len(points)
    n_cells = min(n_cells, n2)
    rng = np.random.default_rng(random_state)
    chosen = np.sort(rng.choice(n2, size=n_cells, replace=False))
    centres = points[chosen]
    owner = nearest_rows(points, centres)
    owner[chosen] = np.arange(n_cells)  # no cell is empty, even with duplicate points
    radius = np.zeros(n_cells)
    np.maximum.at(radius, owner, np.linalg.norm(points - centres[owner], axis=1))
    order = np.argsort(owner, kind="stable")
    bounds = np.searchsorted(owner[order], np.arange(n_cells + 1))
    group = nearest_rows(queries, centres)
    q_order = np.argsort(group, kind="stable")
    q_bounds = np.searchsorted(group[q_order], np.arange(n_cells + 1))
    sq_c = np.einsum("ij,ij->i", centres, centres)
    sq_p = np.einsum("ij,ij->i", points, points)
    out = np.empty(len(queries), dtype=np.int64)
    for c in np.flatnonzero(np.diff(q_bounds)):
        rows = q_order[q_bounds[c]:q_bounds[c + 1]]
        q = queries[rows]
        sq_q = np.einsum("ij,ij->i", q, q)
        own = order[bounds[c]:bounds[c + 1]]  # never empty: the centre itself is in it
        best = np.sqrt(np.maximum((sq_p[own][None, :] - 2.0 * q @ points[own].T).min(axis=1) + sq_q, 0.0))
        to_centres = np.sqrt(np.maximum(sq_c[None, :] - 2.0 * q @ centres.T + sq_q[:, None], 0.0))
        open_cells = np.flatnonzero((to_centres - radius[None, :] <= best[:, None] * (1 + 1e-9)).any(axis=0))
        cand = np.concatenate([order[bounds[o]:bounds[o + 1]] for o in open_cells])
        out[rows] = cand[np.argmin(sq_p[cand][None, :] - 2.0 * q @ points[cand].T, axis=1)]
    return out


def nearest_vertices(queries: np.ndarray, points: np.ndarray, *, random_state: int | None = 0) -> np.ndarray:
    """Exact nearest row of ``points`` ``(n2, d)`` for each of ``queries`` ``(n1, d)``.

    Brute force (:func:`nearest_rows`), pruned by cells above :data:`PRUNE_ABOVE` points
    (:func:`_nearest_rows_pruned`, seeded by ``random_state``; the same answer up to ties).
    """
    if len(points) > PRUNE_ABOVE:
        return _nearest_rows_pruned(queries, points, random_state=random_state)
    return nearest_rows(queries, points)

