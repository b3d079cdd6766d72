"""The map of two coarse copies lifted to every vertex of the meshes (coarse to fine at any size).

Above a size (:func:`meshcorr.core.coarse.needs_copy`) the pipeline runs on
coarse copies of a few thousand vertices, ZoomOut and smooth shells
included (:mod:`meshcorr.stages.refine`, :mod:`meshcorr.stages.shells`),
and this stage carries the refined coarse map :math:`T_c` to the meshes in
time and memory linear in the vertex count: no Laplace-Beltrami
eigenproblem, no matrix with a row per vertex wider than the product space
below, on the meshes.

1. **Extended bases** (in the spirit of the fast approximate eigenbases of
   Nasikun, Brandt & Hildebrandt, "Fast Approximation of Laplace-Beltrami
   Eigenproblems", Computer Graphics Forum (SGP) 2018, which solve on a
   reduced space of functions attached to a few vertices and extend the
   result to all; here the reduced space is the coarse copy's
   piecewise-linear functions): each fine vertex :math:`f` is projected on the
   nearest point of the coarse surface (libigl's AABB tree), and its
   barycentric weights in that coarse triangle form a sparse
   interpolation matrix :math:`P` ``(n, m)`` with three entries a row
   (:func:`interpolation_matrix`); the coarse basis extends as
   :math:`\\Phi = P \\Phi_c` (:func:`extended_basis`), piecewise linear
   over the coarse triangles.
2. **The last shell, fitted on the copies**: the shells' last step
   (:mod:`meshcorr.stages.shells`) with the coarse map: the rigid motion
   :math:`R` of the source copy onto its images, the smooth deformation
   :math:`D_c = \\Phi_{1c}^\\top M_{1c} (X_{2c}[T_c] - R X_{1c})` in the
   first :math:`K` functions, and the orthogonal functional map
   :math:`C = \\arg\\min \\lVert \\Phi_{1c} C - \\Phi_{2c}[T_c] \\rVert`.
   Both shapes are in the units of the fine mesh (unit area, centred), so
   the fitted motion applies to the fine vertices unchanged.
3. **Local nearest neighbours on the meshes**: every fine source vertex is
   deformed, :math:`Y = R X_1 + P_1 \\Phi_{1c} D_c`, and goes to the fine
   target vertex nearest in the shells' product space
   :math:`[\\,Y,\\; w_n n(Y),\\; w_s P_1\\Phi_{1c} C\\,]` against
   :math:`[\\,X_2,\\; w_n n(X_2),\\; w_s P_2 \\Phi_{2c}\\,]`
   (the weights of :mod:`meshcorr.stages.shells`). The search is local:
   the :data:`N_CANDIDATES` target vertices nearest in the first
   :data:`SEARCH_DIMS` columns (coordinates, normals and the first
   spectral coordinates; a KD-tree, approximate to a factor
   ``1 + SEARCH_EPS`` in distance) are ranked by the whole product-space
   distance. With the coordinates and normals alone (6 columns) the
   spectral term could not act and the error at the lion pair's markers
   was 0.017 at 80k vertices; with 30 columns 0.0141, the exact search of
   the full-resolution shells' 0.0143 (``benchmarks/RESULTS-scale.md``).
4. **Refits** (:data:`ITERATIONS`): the motion, the deformation and
   :math:`C` fitted again on :data:`N_SAMPLE` sampled fine vertices and
   their images under the new map (the bases there are rows of
   :math:`P \\Phi_c`), and step 3 repeated.

Cost at ``n`` fine vertices: the AABB queries :math:`O(n \\log m)`, the
KD-tree :math:`O(n \\log n)`, arrays of :math:`O(n K)`. The copies' bases
are those of the coarse run's refinement (kept on the copies).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.spatial import cKDTree

from ..core.coarse import CoarseCopy
from ..core.map_orientation import orientation_score
from ..core.mesh import Mesh
from ..core.orientation import mesh_orientation, vertex_normals
from ..runtime.checks import check_int, check_vertex_map
from ..runtime.threads import kdtree_query
from ..spectral.basis import basis_size, orthogonal_fit, pair_bases
from .refine import REFINE_K, REFINED_MAP
from .shells import DESCRIPTOR_WEIGHT, NORMAL_WEIGHT, SPECTRAL_WEIGHT, rigid_motion

__all__ = ["ITERATIONS", "LIFT_ABOVE", "LIFT_K_FACTOR", "N_CANDIDATES", "N_SAMPLE", "SEARCH_DIMS", "SEARCH_EPS",
           "extended_basis", "interpolation_matrix", "lift_to_fine", "local_nearest"]

#: Vertices (of the larger mesh) above which the pipeline lifts the copies' map with this stage
#: instead of refining it by ZoomOut and the shells on the meshes: those need the meshes' own bases
#: and exact searches (the lion pair at 80k vertices: 59.7 s end to end that way, 9.0 s with the lift,
#: marker error 0.0143 and 0.0141; benchmarks/RESULTS-scale.md), while far below it a copy 5x coarser than the mesh gave a 2x larger error (a 2000-vertex
#: creature from 400-vertex copies, tests/pipeline/test_coarse_to_fine.py).
LIFT_ABOVE = 50_000
#: The lift's basis size, in multiples of the refinement's ``refine_k``.
LIFT_K_FACTOR = 2
#: Target vertices, nearest in coordinates and normals, among which each source vertex takes the
#: nearest in the whole product space.
N_CANDIDATES = 8
#: Refits of the last shell on the fine map after the first lift.
ITERATIONS = 2
#: Fine source vertices sampled (seeded) for each refit.
N_SAMPLE = 20_000
#: Columns of the product space searched by the KD-tree.
SEARCH_DIMS = 30
#: Relative error allowed to the KD-tree's candidates (scipy's ``eps``).
SEARCH_EPS = 1.0
#: Rows per KD-tree query or nearest-point search: bounds the results' memory and the wait for a Ctrl-C.
_QUERY_BLOCK = 1 << 15
#: Source vertices ranked per block (bounds the (block, N_CANDIDATES, d) float32 temporary to ~25 MB).
_BLOCK = 1 << 12


def interpolation_matrix(points: np.ndarray, coarse: Mesh) -> sp.csr_matrix:
    """``(n, m)`` sparse: barycentric weights of each point's nearest point on the coarse surface.

    Parameters
    ----------
    points : (n, 3) float
        E.g. the vertices of the fine mesh the copy was made from.
    coarse : Mesh
        A triangle mesh of ``m`` vertices.

    Returns
    -------
    P : (n, m) csr_matrix
        Row i holds the barycentric coordinates :math:`(u, v, w) \\ge 0`,
        :math:`u + v + w = 1`, of the point of the coarse surface nearest to
        ``points[i]`` in its triangle's three vertices, so that ``P @ f``
        interpolates a function ``f`` ``(m, ...)`` of the coarse vertices
        linearly over the coarse triangles.
    """
    import igl  # libigl's AABB tree: no other library in use finds nearest points on triangles

    points = np.ascontiguousarray(points, dtype=np.float64)
    vertices = np.ascontiguousarray(coarse.vertices, dtype=np.float64)
    faces = np.ascontiguousarray(coarse.faces, dtype=np.int64)
    face, closest = np.empty(len(points), dtype=np.int64), np.empty_like(points)
    for start in range(0, len(points), _QUERY_BLOCK):  # blocks: libigl holds the interpreter (Ctrl-C)
        rows = slice(start, start + _QUERY_BLOCK)
        _, face[rows], closest[rows] = igl.point_mesh_squared_distance(points[rows], vertices, faces)
    corners = faces[face]  # (n, 3)
    weights = _barycentric(closest, vertices[corners[:, 0]], vertices[corners[:, 1]], vertices[corners[:, 2]])
    rows = np.repeat(np.arange(len(points)), 3)
    return sp.csr_matrix((weights.ravel(), (rows, corners.ravel())), shape=(len(points), len(vertices)))


def _barycentric(p: np.ndarray, a: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
    """``(n, 3)`` barycentric coordinates of points ``p`` in triangles ``(a, b, c)``, clipped to the triangle.

    The normal equations of :math:`p - a = v (b - a) + w (c - a)` (Ericson, "Real-Time
    Collision Detection", 3.4), written out because they vectorise over all rows at once; a
    degenerate triangle gives its first corner.
    """
    e0, e1, e2 = b - a, c - a, p - a
    d00, d01, d11 = (np.einsum("ij,ij->i", x, y) for x, y in ((e0, e0), (e0, e1), (e1, e1)))
    d20, d21 = np.einsum("ij,ij->i", e2, e0), np.einsum("ij,ij->i", e2, e1)
    denominator = d00 * d11 - d01 * d01
    good = denominator > 1e-30 * np.maximum(d00 * d11, 1e-300)
    safe = np.where(good, denominator, 1.0)
    v = np.where(good, (d11 * d20 - d01 * d21) / safe, 0.0)
    w = np.where(good, (d00 * d21 - d01 * d20) / safe, 0.0)
    weights = np.clip(np.stack([1.0 - v - w, v, w], axis=1), 0.0, None)
    return weights / weights.sum(axis=1, keepdims=True)


def extended_basis(interpolation: sp.spmatrix, basis: np.ndarray) -> np.ndarray:
    """``(n, k)``: a coarse basis ``(m, k)`` extended to the fine vertices, :math:`P \\Phi_c`.

    Approximately orthonormal for the fine mass matrix (:math:`\\Phi^\\top M \\Phi \\approx I`,
    the closer the finer the copy); the lift does not need it exactly.
    """
    return np.asarray(interpolation @ np.asarray(basis, dtype=np.float64))


def lift_to_fine(copies: tuple[CoarseCopy, CoarseCopy], coarse_map: np.ndarray, *, k: int = REFINE_K,
                 landmarks: np.ndarray | None = None,
                 descriptors: tuple[np.ndarray, np.ndarray] | None = None,
                 n_candidates: int = N_CANDIDATES, iterations: int = ITERATIONS, n_sample: int = N_SAMPLE,
                 search_dims: int = SEARCH_DIMS, eps: float = SEARCH_EPS, spectral_k: int | None = None,
                 first_k: int | None = None, random_state: int | None = 0, progress=None) -> np.ndarray:
    """The refined map of two coarse copies as a map between the fine meshes (module docstring).

    Parameters
    ----------
    copies : (CoarseCopy, CoarseCopy)
        Source and target copies (``copy.fine``: the meshes, ``n1`` and ``n2`` vertices).
    coarse_map : (m1,) int
        Target coarse vertex of each source coarse vertex (the copies' refined map).
    k : int
        Basis size :math:`K` (the copies' refinement bases; clipped to their sizes).
    landmarks : (L, 2) int, optional
        (source, target) fine vertex pairs held in the map.
    descriptors : ((m1, d), (m2, d)) float, optional
        Descriptors of the copies' vertices that should agree at
        corresponding points (the landmarks' geodesic distances over their
        mean), interpolated to the fine vertices and appended to the product
        space with the shells' weight.
    n_candidates : int
        Nearest target vertices in coordinates and normals ranked in the whole space.
    search_dims, eps : int, float
        Columns searched by the KD-tree, and its relative error allowed (:func:`local_nearest`).
    spectral_k, first_k : int, optional
        Spectral coordinates in the product space, and the deformation's basis size at the first
        pass (rising to ``k`` at the last); both ``k`` by default.
    random_state : int or None
        Seed of the bases' start vectors, of the orientation's sample and of the refits' samples.
    progress : callable, optional
        ``progress(done, total)`` after each of the ``iterations + 1`` searches.

    Returns
    -------
    mapping : (n1,) int
        Target vertex of each fine source vertex.
    """
    one, two = copies
    c1, c2 = one.mesh, two.mesh
    coarse_map = check_vertex_map(coarse_map, c1.n_vertices, c2.n_vertices, messages=REFINED_MAP).astype(np.int64)
    n_candidates = check_int("n_candidates", n_candidates, minimum=1)
    iterations = check_int("iterations", iterations, minimum=0)
    k = basis_size(k, c1, c2)
    spectral_k = k if spectral_k is None else spectral_k
    first_k = k if first_k is None else first_k
    phi1c, phi2c = pair_bases(c1, c2, k, random_state=random_state)
    # Both shapes in the fine mesh's units: unit area, centred (as the shells' _unit_shape).
    faces1, faces2 = mesh_orientation(one.fine).faces, mesh_orientation(two.fine).faces
    (x1, m1, unit1), (x2, _, unit2) = _unit_fine(one.fine, faces1), _unit_fine(two.fine, faces2)
    x1c, x2c = unit1(c1.vertices), unit2(c2.vertices)
    mass = np.asarray(vertex_normals(np.asarray(c1.vertices, dtype=np.float64), c1.faces)[1])
    mass = mass / mass.sum()
    # Whether the map keeps or mirrors the orientation: a rotation or a reflection (meshcorr.stages.shells).
    side = 1.0 if orientation_score(c1, c2, coarse_map, random_state=random_state) >= 0.5 else -1.0
    # No (n, k) basis is kept: P (Phi_c A) for whatever A, the interpolation being linear.
    P1 = interpolation_matrix(one.fine.vertices, c1).astype(np.float32)
    P2 = interpolation_matrix(two.fine.vertices, c2).astype(np.float32)
    spectral = min(spectral_k, k)
    columns = [x2, NORMAL_WEIGHT * vertex_normals(x2, faces2)[0]]
    width = 6 + spectral + (0 if descriptors is None else np.shape(descriptors[0])[1])
    points = _product_space(len(x2), width, columns, P2, SPECTRAL_WEIGHT * phi2c[:, :spectral],
                            None if descriptors is None else DESCRIPTOR_WEIGHT * np.asarray(descriptors[1]))
    del columns
    # The first fit on the copies (their map, masses and bases); then each refit on a seeded
    # sample of the fine map (the fine vertices' masses, the bases interpolated there).
    fit = (x1c, x2c[coarse_map], mass, phi1c, phi2c[coarse_map])
    rng = np.random.default_rng(random_state)
    mapping = None
    for step, size in enumerate(np.linspace(min(first_k, k), k, iterations + 1).round().astype(int)):
        p1, images, weights, basis, image_basis = fit
        rigid = rigid_motion(p1, images, weights, side)
        deformation = basis[:, :size].T @ (weights[:, None] * (images - rigid(p1)))  # (size, 3), in the basis
        C = orthogonal_fit(basis[:, :spectral], image_basis[:, :spectral])  # Phi1 C ~ Phi2[T]
        deformed = rigid(x1) + P1 @ (phi1c[:, :size] @ deformation).astype(np.float32)
        columns = [deformed, side * NORMAL_WEIGHT * vertex_normals(deformed, faces1)[0]]
        del deformed
        queries = _product_space(len(x1), width, columns, P1, SPECTRAL_WEIGHT * (phi1c[:, :spectral] @ C),
                                 None if descriptors is None else DESCRIPTOR_WEIGHT * np.asarray(descriptors[0]))
        del columns
        mapping = local_nearest(queries, points, n_candidates, search_dims, eps)
        del queries
        if landmarks is not None and len(landmarks):
            landmarks = np.asarray(landmarks)
            mapping[landmarks[:, 0]] = landmarks[:, 1]
        sample = np.sort(rng.choice(len(x1), size=min(n_sample, len(x1)), replace=False))
        images = mapping[sample]
        fit = (x1[sample], x2[images], m1[sample] / m1[sample].sum(), P1[sample] @ phi1c, P2[images] @ phi2c)
        if progress is not None:
            progress(step + 1, iterations + 1)
    return mapping


def _product_space(n: int, width: int, columns: list, interpolation: sp.spmatrix, spectral: np.ndarray,
                   descriptors: np.ndarray | None) -> np.ndarray:
    """``(n, width)`` float32: the coordinate and normal columns, then ``P spectral`` and ``P descriptors``."""
    out = np.empty((n, width), dtype=np.float32)
    out[:, :6] = np.hstack(columns)
    k = spectral.shape[1]
    out[:, 6:6 + k] = interpolation @ spectral.astype(np.float32)
    if descriptors is not None:
        out[:, 6 + k:] = interpolation @ descriptors.astype(np.float32)
    return out


def local_nearest(queries: np.ndarray, points: np.ndarray, n_candidates: int = N_CANDIDATES,
                  search_dims: int = SEARCH_DIMS, eps: float = SEARCH_EPS) -> np.ndarray:
    """``(n1,)`` int: for each query row, the nearest of the ``n_candidates`` points nearest in its first 6 columns.

    Parameters
    ----------
    queries : (n1, d) float
    points : (n2, d) float
        ``d >= 6``; the first six columns (coordinates and weighted normals) are searched by a
        KD-tree, the candidates then ranked by the whole squared Euclidean distance.
    """
    n_candidates = min(n_candidates, len(points))
    tree = cKDTree(points[:, :search_dims])
    out = np.empty(len(queries), dtype=np.int64)
    for start in range(0, len(queries), _QUERY_BLOCK):
        block = queries[start:start + _QUERY_BLOCK]
        # over the cores, and safe under Ctrl-C (meshcorr.runtime.threads.kdtree_query)
        _, candidates = kdtree_query(tree, block[:, :search_dims], k=n_candidates, eps=eps)
        candidates = candidates.reshape(len(block), n_candidates)
        for first in range(0, len(block), _BLOCK):
            rows = candidates[first:first + _BLOCK]
            gaps = points[rows] - block[first:first + _BLOCK, None, :]
            best = np.argmin(np.einsum("ijk,ijk->ij", gaps, gaps), axis=1)
            out[start + first:start + first + len(rows)] = rows[np.arange(len(rows)), best]
    return out


def _unit_fine(mesh: Mesh, faces: np.ndarray):
    """The mesh's coordinates at unit area, centred on the area-weighted centroid, its unit-sum masses, and
    the same transformation as a function (for the copy's vertices)."""
    vertices = np.asarray(mesh.vertices, dtype=np.float64)
    areas = np.asarray(vertex_normals(vertices, faces)[1])
    total = float(areas.sum())
    mass = areas / total
    centre, scale = mass @ vertices, np.sqrt(total)
    unit = lambda x: (np.asarray(x, dtype=np.float64) - centre) / scale  # noqa: E731
    return unit(vertices), mass, unit
