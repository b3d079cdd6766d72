"""Point clouds: their validation and their neighbourhood graphs.

A point cloud is a :class:`~meshcorr.core.mesh.Mesh` with no faces
(``mesh.is_cloud``). Where the pipeline uses a mesh's triangles, a cloud
uses the neighbourhoods of its points, each computation dispatching on
``is_cloud`` in one place: geodesics (:mod:`meshcorr.core.geodesics`, the heat
method on clouds), the Laplace-Beltrami operator and vertex areas
(:mod:`meshcorr.core.laplacian`), normals and their outward orientation
(:mod:`meshcorr.core.normals`, through :mod:`meshcorr.core.orientation`), and the
graph of neighbouring vertices (:func:`edges`, here).

Two neighbourhoods are used:

- the :data:`N_NEIGHBORS` (30) nearest points, on which the cloud Laplacian
  of Sharp & Crane (2020) and potpourri3d's point-cloud heat solver build
  their local triangulations: their graph decides whether a cloud is
  connected (:func:`validate_cloud`);
- the "one-ring" of a point, where a mesh would use its edges (the
  smoothing of the extremity detector, continuity of a map, part colours,
  Dijkstra distances): the :data:`RING_NEIGHBORS` (8) nearest points plus
  the edges of a minimum spanning tree of the 30-neighbour graph, so that
  it is connected whenever the cloud is. A k-nearest-neighbour graph joined
  with a spanning tree is the "Riemannian graph" of Hoppe, DeRose, Duchamp,
  McDonald & Stuetzle, "Surface reconstruction from unorganized points"
  (SIGGRAPH 1992).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components, minimum_spanning_tree
from scipy.spatial import cKDTree

from ..errors import MeshError
from .validate import as_array, check_finite, check_scale, plural, which

__all__ = ["N_NEIGHBORS", "RING_NEIGHBORS", "MIN_POINTS", "edges", "knn_graph", "triangulation_failed",
           "validate_cloud"]

#: Neighbours of the cloud Laplacian and heat solver, and of the connectivity check.
N_NEIGHBORS = 30
#: Neighbours that stand for a mesh vertex's one-ring (plus a spanning tree, see :func:`edges`).
RING_NEIGHBORS = 8
#: Fewest points of a cloud: one point and its N_NEIGHBORS neighbours.
MIN_POINTS = N_NEIGHBORS + 1
#: A cloud whose second principal extent is below this fraction of the first is a line.
_FLAT_RTOL = 1e-9
#: A point whose :data:`N_NEIGHBORS` neighbours' second principal extent is below this fraction of
#: the first lies on a curve, not a surface (a surface sample's neighbourhood: 0.3-1).
_CURVE_RTOL = 1e-3
#: Share of such points from which a cloud is refused: it samples curves (the local triangulation
#: of potpourri3d's solvers then fails; a 300-point line with one point off it was measured).
_CURVE_SHARE = 0.5


def knn_graph(points: np.ndarray, k: int) -> sp.csr_matrix:
    """Symmetric graph of the ``k`` nearest neighbours, weighted by distance.

    Parameters
    ----------
    points : (n, 3) float
        Distinct points.
    k : int
        Neighbours per point (clipped to ``n - 1``).

    Returns
    -------
    graph : (n, n) sparse float
        ``graph[i, j]`` is ``|x_i - x_j|`` when j is among the k nearest
        points of i or i among those of j, else no entry.
    """
    n = len(points)
    k = max(1, min(int(k), n - 1))
    distance, index = cKDTree(points).query(points, k=k + 1)
    rows = np.repeat(np.arange(n), k)
    graph = sp.coo_matrix((distance[:, 1:].ravel(), (rows, index[:, 1:].ravel())), shape=(n, n)).tocsr()
    return graph.maximum(graph.T).tocsr()


def _cloud_edges(points: np.ndarray) -> np.ndarray:
    """The one-ring edges of a cloud (module docstring), ``(e, 2)`` sorted pairs."""
    ring = knn_graph(points, RING_NEIGHBORS)
    # Distinct points have positive distances, so every neighbour pair is an explicit entry.
    tree = minimum_spanning_tree(knn_graph(points, N_NEIGHBORS))
    both = (ring + tree + tree.T).tocoo()
    pairs = np.column_stack([both.row, both.col]).astype(np.int64)
    pairs = np.sort(pairs[pairs[:, 0] != pairs[:, 1]], axis=1)
    return np.unique(pairs, axis=0)


def edges(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """The graph of neighbouring vertices: a mesh's edges, or a cloud's one-ring.

    Parameters
    ----------
    vertices : (n, 3) float
    faces : (m, 3) int
        Triangles; ``m = 0`` for a point cloud.

    Returns
    -------
    edges : (e, 2) int64
        Distinct undirected edges ``(i, j)``, ``i < j``, sorted: the edges of
        the triangles, or for a cloud its :data:`RING_NEIGHBORS` nearest
        points joined with a spanning tree of its :data:`N_NEIGHBORS` graph
        (module docstring).
    """
    faces = np.asarray(faces, dtype=np.int64).reshape(-1, 3)
    if len(faces) == 0:
        return _cloud_edges(np.asarray(vertices, dtype=np.float64))
    pairs = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
    return np.unique(np.sort(pairs, axis=1), axis=0)


def _check_extent(points: np.ndarray, name: str) -> None:
    """Refuse a cloud whose points all coincide or lie on one line: it spans no surface."""
    centred = points - points.mean(axis=0)
    extent = np.linalg.svd(centred, compute_uv=False)
    if extent[0] == 0.0:
        raise MeshError(f"{name}: all {len(points)} points coincide (the cloud has zero extent), so they "
                        "sample no surface. Check the file or the array (a unit or parsing problem?).")
    if extent[1] <= _FLAT_RTOL * extent[0]:
        raise MeshError(f"{name}: all {len(points)} points lie on one straight line, so they sample no "
                        "surface. A point cloud must sample a surface in 3-D.")


def _check_curves(points: np.ndarray, name: str) -> None:
    """Refuse a cloud most of whose points have their neighbours on one line: it samples curves."""
    neighbours = cKDTree(points).query(points, k=min(N_NEIGHBORS + 1, len(points)))[1]
    patches = points[neighbours]
    extent = np.linalg.svd(patches - patches.mean(axis=1, keepdims=True), compute_uv=False)
    on_curves = extent[:, 1] <= _CURVE_RTOL * extent[:, 0]
    if on_curves.mean() >= _CURVE_SHARE:
        raise MeshError(f"{name}: {on_curves.sum()} of its {len(points)} points have their {N_NEIGHBORS} nearest "
                        "neighbours on one straight line, so the cloud samples lines, not a surface. A point "
                        "cloud must sample a surface in 3-D densely enough that each point's neighbours "
                        "spread in two directions.")


def triangulation_failed(error: RuntimeError, what: str) -> MeshError:
    """The error to raise when a cloud solver of potpourri3d / robust_laplacian refuses the points.

    Their local triangulations (geometry-central) assert on neighbourhoods that span no triangle;
    :func:`validate_cloud` refuses the clouds known to do that, and this names any other case
    instead of an internal error.
    """
    detail = str(error).strip().splitlines()[0][-160:] if str(error).strip() else type(error).__name__
    return MeshError(f"The point cloud's local triangulation for {what} failed ({detail}): some points' "
                     "neighbourhoods span no surface (points on lines, or very uneven sampling). Sample the "
                     "surface more evenly, or pass a mesh.")


def _check_duplicates(points: np.ndarray, name: str) -> None:
    """Refuse repeated points: a cloud's neighbourhoods and Laplacian need distinct points."""
    _, first, inverse = np.unique(points, axis=0, return_index=True, return_inverse=True)
    repeats = np.flatnonzero(first[inverse.ravel()] != np.arange(len(points)))
    if len(repeats):
        raise MeshError(
            f"{name}: {plural(len(repeats), 'point')} repeat{'s' if len(repeats) == 1 else ''} an earlier "
            f"point ({which('point', 'points', repeats)}); a point cloud needs distinct points (the "
            "neighbourhoods of its Laplacian and geodesics degenerate). Remove the duplicates first "
            "(e.g. numpy.unique(points, axis=0), or MeshLab: Filters > Cleaning and Repairing > "
            "Remove Duplicate Vertices).")


def _select_cluster(points: np.ndarray, largest_component: bool, name: str) -> np.ndarray:
    """Indices of the points kept: all, or those of the largest cluster of the neighbour graph."""
    n = len(points)
    count, labels = connected_components(knn_graph(points, N_NEIGHBORS), directed=False)
    if count == 1:
        return np.arange(n, dtype=np.int64)
    sizes = np.bincount(labels)
    if not largest_component:
        listed = ", ".join(str(s) for s in np.sort(sizes)[::-1][:5])
        raise MeshError(
            f"{name} falls apart into {count} separate clusters of points (no point of one is among the "
            f"{N_NEIGHBORS} nearest of a point of another; point counts, largest first: {listed}"
            f"{', ...' if count > 5 else ''}); a correspondence needs a single connected surface. Pass "
            "--largest-component (CLI) / largest_component=True (API) to keep only the largest cluster.")
    # Ties go to the cluster holding the lowest point index (np.argmax is first).
    return np.flatnonzero(labels == labels[np.argmax(sizes[labels] == sizes.max())]).astype(np.int64)


def validate_cloud(points, *, min_vertices: int = 3, largest_component: bool = False, name: str = "cloud",
                   reason: str | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Check a point cloud and return clean arrays, optionally its largest cluster.

    The checks, in order: shape ``(n, 3)`` of real numbers, no NaN or inf,
    at least :data:`MIN_POINTS` points, a cloud that is neither a single
    point nor a line, no repeated points (refused, not merged: merging would
    leave input points without an image in the map), and one connected
    cluster in the graph of the :data:`N_NEIGHBORS` nearest points (or only
    its largest cluster kept with ``largest_component``), with at least
    ``min_vertices`` points, and a cloud that does not lie mostly on lines
    (a sampled curve or wireframe: :func:`_check_curves`). A flat cloud is accepted (like a flat mesh, its
    outside is then undefined: :mod:`meshcorr.core.normals` says so).

    Parameters
    ----------
    points : (n, 3) float
    min_vertices : int
        Fewest points the kept cloud may have (at least :data:`MIN_POINTS` apply anyway).
    largest_component : bool
        Keep the largest cluster instead of raising on several.
    name : str
        How messages refer to the cloud.
    reason : str, optional
        Why ``min_vertices`` are needed, quoted in the message.

    Returns
    -------
    points : (n', 3) float64
        A copy of the kept points, in their input order.
    kept : (n',) int64
        Input index of each kept point.

    Raises
    ------
    MeshError
        Naming the problem, the points concerned and the fix.
    """
    points = as_array(points, "points", "(n, 3)", "Pass one row of x, y, z coordinates per point.", name)
    if points.size == 0:
        raise MeshError(f"{name} is empty: it has no points. Check that the file holds a mesh or a point cloud.")
    if points.ndim != 2 or points.shape[1] != 3:
        raise MeshError(f"{name}: points must have shape (n, 3); got {points.shape}. "
                        "Pass one row of x, y, z coordinates per point.")
    if not np.issubdtype(points.dtype, np.number) or np.iscomplexobj(points):
        raise MeshError(f"{name}: point coordinates must be real numbers; got dtype {points.dtype}.")
    points = np.array(points, dtype=np.float64)
    check_finite(points, name)
    check_scale(points, name)
    fewest = max(MIN_POINTS, int(min_vertices))

    def check_count(count: int) -> None:
        if count < fewest:
            why = f" ({reason})" if reason and min_vertices >= MIN_POINTS else ""
            raise MeshError(
                f"{name} is a point cloud of {count} points but at least {fewest} are needed{why}: its "
                f"Laplacian, geodesics and normals are built on the {N_NEIGHBORS} nearest neighbours of "
                "each point. Sample the surface more densely.")

    check_count(len(points))
    _check_extent(points, name)
    _check_duplicates(points, name)
    kept = _select_cluster(points, largest_component, name)
    check_count(len(kept))
    _check_curves(points[kept], name)
    return points[kept], kept
