"""Geodesic distances on triangle meshes.

One seam for every solver: :func:`geodesic_solver` returns an object with a
``distances(sources)`` method, so the pipeline never depends on which library
computes the distances.

Solvers
-------
``"heat"``
    The heat method (Crane, Weischedel & Wardetzky 2013) through
    potpourri3d's ``MeshHeatMethodDistanceSolver`` (intrinsic Delaunay
    "robust" variant). About 2-3 % mean error; fastest accurate solver.
``"fmm"``
    Fast marching (Kimmel & Sethian 1998), the paper's choice, through
    potpourri3d's ``MeshFastMarchingDistanceSolver``. About 1-2 % error.
``"exact"``
    The exact polyhedral geodesic of Mitchell, Mount & Papadimitriou
    (MMP) through the optional ``pygeodesic`` package
    (``pip install meshcorr[exact]``). Exact but ~100x slower: use it for
    ground truth on small meshes.
``"dijkstra"``
    Shortest paths along mesh edges (scipy.sparse.csgraph). Fast but
    overestimates by ~10 %; kept as a cheap reference.

Point clouds (no faces) take ``"heat"``, the heat method on clouds of
potpourri3d's ``PointCloudHeatSolver`` (Sharp & Crane 2020: the heat
method on the tufted cover of local triangulations, the same construction
as the cloud Laplacian of :mod:`meshcorr.core.laplacian`; measured on TOSCA
cat0's 5000 vertices: within 0.7 % on average of the mesh's heat
distances), or ``"dijkstra"`` along the cloud's neighbour graph
(:func:`meshcorr.core.pointcloud.edges`). Fast marching and MMP need triangles:
they refuse a cloud.
"""

from __future__ import annotations

from typing import Callable, Protocol

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import dijkstra

from ..errors import ParameterError
from .pointcloud import edges as graph_edges
from .pointcloud import triangulation_failed

GEODESIC_METHODS = ("heat", "fmm", "exact", "dijkstra")
#: The default solver (of :class:`meshcorr.Settings` and every function that takes ``geodesic``).
DEFAULT_GEODESIC = "heat"
#: The solvers that work on point clouds.
CLOUD_GEODESIC_METHODS = ("heat", "dijkstra")

ProgressFn = Callable[[int, int], None]


class GeodesicSolver(Protocol):
    """Computes geodesic distances from source vertices to every vertex."""

    n_vertices: int

    def distances(self, sources: np.ndarray) -> np.ndarray:
        """Distances from each source to every vertex, ``(len(sources), n)``."""


class _PerSourceSolver:
    """Wraps a single-source solve ``f(i) -> (n,)`` into the batched interface."""

    def __init__(self, n_vertices: int, solve_one: Callable[[int], np.ndarray],
                 progress: ProgressFn | None = None) -> None:
        self.n_vertices = n_vertices
        self._solve_one = solve_one
        self.progress = progress

    def distances(self, sources: np.ndarray) -> np.ndarray:
        sources = np.asarray(sources, dtype=np.int64).reshape(-1)
        out = np.empty((sources.size, self.n_vertices), dtype=np.float64)
        step = max(1, sources.size // 100)
        for row, s in enumerate(sources):
            out[row] = self._solve_one(int(s))
            if self.progress is not None and (row % step == 0 or row == sources.size - 1):
                self.progress(row + 1, sources.size)
        # Approximate solvers may return tiny negatives or a non-zero value at
        # the source itself: clamp to the metric's obvious constraints.
        np.maximum(out, 0.0, out=out)
        out[np.arange(sources.size), sources] = 0.0
        return out


class _DijkstraSolver:
    def __init__(self, vertices: np.ndarray, faces: np.ndarray) -> None:
        self.n_vertices = len(vertices)
        edges = graph_edges(vertices, faces)  # a mesh's edges, or a cloud's neighbour graph
        lengths = np.linalg.norm(vertices[edges[:, 0]] - vertices[edges[:, 1]], axis=1)
        n = self.n_vertices
        self._graph = sp.coo_matrix((lengths, (edges[:, 0], edges[:, 1])), shape=(n, n)).tocsr()

    def distances(self, sources: np.ndarray) -> np.ndarray:
        sources = np.asarray(sources, dtype=np.int64).reshape(-1)
        return dijkstra(self._graph, directed=False, indices=sources)


def geodesic_solver(vertices: np.ndarray, faces: np.ndarray, method: str = "heat",
                    *, progress: ProgressFn | None = None) -> GeodesicSolver:
    """Build a geodesic distance solver for a mesh.

    Parameters
    ----------
    vertices : (n, 3) float
        Vertex positions.
    faces : (m, 3) int
        Triangles, indices into ``vertices``; ``m = 0`` for a point cloud.
    method : {"heat", "fmm", "exact", "dijkstra"}
        Which solver to use (see the module docstring); a cloud takes "heat" or "dijkstra".
    progress : callable, optional
        Called as ``progress(done, total)`` while a batch of sources is solved.

    Returns
    -------
    solver : GeodesicSolver
        ``solver.distances(sources)`` returns a ``(len(sources), n)`` array.
    """
    vertices = np.ascontiguousarray(vertices, dtype=np.float64)
    faces = np.ascontiguousarray(faces, dtype=np.int64).reshape(-1, 3)
    n = len(vertices)
    if len(faces) == 0 and method in GEODESIC_METHODS and method not in CLOUD_GEODESIC_METHODS:
        raise ParameterError(
            f"The {method!r} geodesic solver needs triangles; a point cloud has none. Use geodesic='heat' "
            "(--geodesic heat), the heat method on point clouds, or 'dijkstra' (its neighbour graph).")
    if len(faces) == 0 and method == "heat":
        import potpourri3d as pp3d

        try:
            cloud = pp3d.PointCloudHeatSolver(vertices)
        except RuntimeError as error:
            raise triangulation_failed(error, "its geodesics (the heat method)") from None
        return _PerSourceSolver(n, cloud.compute_distance, progress)
    if method == "heat":
        import potpourri3d as pp3d

        heat = pp3d.MeshHeatMethodDistanceSolver(vertices, faces)
        return _PerSourceSolver(n, heat.compute_distance, progress)
    if method == "fmm":
        import potpourri3d as pp3d

        fmm = pp3d.MeshFastMarchingDistanceSolver(vertices, faces)
        return _PerSourceSolver(n, lambda s: fmm.compute_distance([[(s, [])]]), progress)
    if method == "exact":
        try:
            import pygeodesic.geodesic as pygeodesic
        except ImportError as exc:  # pragma: no cover - depends on the environment
            raise ParameterError(
                "The 'exact' geodesic solver needs the optional package pygeodesic. "
                "Install it with `pip install meshcorr[exact]` or choose geodesic='heat'."
            ) from exc
        exact = pygeodesic.PyGeodesicAlgorithmExact(vertices, faces.astype(np.int32))
        return _PerSourceSolver(n, lambda s: exact.geodesicDistances(np.array([s]))[0], progress)
    if method == "dijkstra":
        return _DijkstraSolver(vertices, faces)
    raise ParameterError(
        f"The 'geodesic' parameter must be one of {', '.join(GEODESIC_METHODS)}. Got {method!r} instead."
    )


def pairwise_geodesics(vertices: np.ndarray, faces: np.ndarray, method: str = "heat",
                       *, progress: ProgressFn | None = None) -> np.ndarray:
    """All-pairs geodesic distance matrix.

    Parameters
    ----------
    vertices : (n, 3) float
    faces : (m, 3) int
    method : {"heat", "fmm", "exact", "dijkstra"}
    progress : callable, optional
        ``progress(done, total)``.

    Returns
    -------
    D : (n, n) float64
        ``D[i, j]`` is the geodesic distance between vertices i and j,
        symmetrised as ``(D + D.T) / 2`` (approximate solvers are not exactly
        symmetric), with a zero diagonal.
    """
    solver = geodesic_solver(vertices, faces, method, progress=progress)
    D = solver.distances(np.arange(len(vertices)))
    # In-place symmetrisation: avoids a second n x n temporary.
    D += D.T
    D *= 0.5
    np.fill_diagonal(D, 0.0)
    return D
