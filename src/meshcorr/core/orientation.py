"""Surface orientation: consistent outward winding and the orientation score of a map.

An intrinsic symmetry (left/right of a person or an animal) is an isometry
that *reverses* orientation, so a map and its mirror image cost the same to
every intrinsic criterion, the spectral cost included (docs/method.md,
"Departures from the paper", the left/right mirror). Orientation tells them apart: with both meshes oriented
outwards, a correct map takes a small counter-clockwise loop around a
source vertex to a counter-clockwise loop around its image, a mirrored map
to a clockwise one.

The score of a vertex map :math:`f` is measured on mapped neighbourhoods.
For a source vertex :math:`i` with outward normal :math:`n_i` and a
right-handed tangent frame :math:`(u_i, v_i)`, :math:`u_i \\times v_i = n_i`,
its ``n_neighbors`` nearest vertices :math:`j` give tangent coordinates
:math:`a_j = ((x_j - x_i) \\cdot u_i, (x_j - x_i) \\cdot v_i)`; the least
squares Jacobian of :math:`f` at :math:`i` pushes :math:`u_i, v_i` to

.. math::

    (c_1, c_2) = \\sum_j (y_{f(j)} - y_{f(i)}) \\, a_j^T
                 \\left(\\sum_j a_j a_j^T\\right)^{-1}

and the map keeps the orientation at :math:`i` when the triple product
:math:`m_{f(i)} \\cdot (c_1 \\times c_2) > 0`, with :math:`m` the target's
outward vertex normal (the positive factor :math:`\\det(\\sum a a^T)^{-1}` is
left out: only the sign counts). The score is the area-weighted fraction of
sampled source vertices whose sign is positive, among those whose
neighbourhood does not collapse onto one target vertex: near 1 for an
orientation-preserving map, near 0 for a mirrored one, near 0.5 for noise.
Using a neighbourhood rather than single triangles makes the test robust to
the vertex-level noise of a nearest-neighbour map.

Winding is repaired with ``trimesh.repair.fix_winding`` (a traversal of the
face adjacency) and turned outwards by the sign of the enclosed volume. For an
open mesh the enclosed volume depends on the reference point (the holes are
not closed). When that sign changes between the centroid and the corners of
the bounding box, each boundary loop is closed by a fan of triangles to its
centroid (for the volume only) and the closed surface's volume, which no
longer depends on the reference point, decides: a part of a closed shape (a
body cut by a plane, one side of a scan that wraps round) then has a
well-defined outside. The orientation is called *unreliable* when even that
volume is below :data:`CAPPED_VOLUME_MIN` of the volume of a sphere of the
same area, e.g. for a disc-like patch.

A point cloud has no triangles: its normals are estimated, turned outwards
and checked by :func:`meshcorr.core.normals.estimate_normals` (principal
components of neighbourhoods after Hoppe et al., turned outwards by
visibility votes and a propagation along the neighbour graph, the same
volume test), and its vertex areas are those of its Laplacian
(:func:`meshcorr.core.laplacian.vertex_areas`); the score is then the same.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

from ..runtime.checks import check_int
from ..errors import ParameterError
from .sampling import farthest_point_sampling
from .mesh import Mesh

#: An open mesh whose capped volume (module docstring) is below this fraction of the volume of a
#: sphere of the same area, :math:`A^{3/2} / (6 \sqrt{\pi})`, has no reliable outside (a flat
#: disc: 0; a hemisphere: 1.4; TOSCA shapes cut to 60-90 % of their area: 0.3-0.8).
CAPPED_VOLUME_MIN = 0.02


@dataclass(frozen=True)
class Orientation:
    """Consistent, outward-facing triangles of a mesh.

    Attributes
    ----------
    faces : (m, 3) int
        The mesh's faces, rows reversed where needed so that every face is
        counter-clockwise seen from outside.
    reliable : bool
        Whether "outside" is well defined (closed mesh, or open with small
        holes; see the module docstring).
    reason : str
        Why not, when ``reliable`` is False; empty otherwise.
    n_flipped : int
        Faces whose winding was reversed.
    """

    faces: np.ndarray
    reliable: bool
    reason: str
    n_flipped: int


def _signed_volumes(vertices: np.ndarray, faces: np.ndarray, origins: np.ndarray) -> np.ndarray:
    """Volume enclosed by the triangles seen from each of ``origins`` ``(o, 3)`` (divergence theorem).

    With :math:`a, b, c` the corners of a face,
    :math:`(a - o) \\cdot ((b - o) \\times (c - o)) = a \\cdot (b \\times c) - o \\cdot ((b - a) \\times (c - a))`,
    so every origin needs only two sums over the faces (taken about the centroid for accuracy).
    """
    centre = vertices.mean(axis=0)
    v = vertices[faces] - centre
    normals = np.cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0])  # (b - a) x (c - a)
    volume = np.einsum("ij,ij->i", v[:, 0], np.cross(v[:, 1], v[:, 2])).sum()
    return (volume - (np.asarray(origins) - centre) @ normals.sum(axis=0)) / 6.0


def orient_outward(vertices: np.ndarray, faces: np.ndarray) -> Orientation:
    """Repair the winding of a triangle mesh and turn it outwards.

    Parameters
    ----------
    vertices : (n, 3) float
    faces : (m, 3) int
        One connected, manifold surface (as :func:`meshcorr.core.validate.validate_mesh`
        guarantees).

    Returns
    -------
    orientation : Orientation
    """
    import trimesh

    tm = trimesh.Trimesh(vertices=np.asarray(vertices, dtype=float), faces=np.array(faces), process=False,
                         validate=False)
    trimesh.repair.fix_winding(tm)
    fixed = np.array(tm.faces, dtype=np.int64)
    if not tm.is_winding_consistent:
        return Orientation(fixed, False, "the surface is not orientable (a Moebius-like strip): "
                           "its triangles cannot all be wound the same way", _n_flipped(faces, fixed))
    V = np.asarray(vertices, dtype=float)
    lo, hi = V.min(axis=0), V.max(axis=0)
    origins = [V.mean(axis=0)] + [np.where(np.array(c, dtype=bool), hi, lo)
                                  for c in np.ndindex(2, 2, 2)]
    volumes = _signed_volumes(V, fixed, np.array(origins))
    if volumes[0] < 0:
        fixed = fixed[:, ::-1].copy()
        volumes = -volumes
    reliable, reason = True, ""
    if not (volumes > 0).all():
        capped = _capped_volume(V, fixed)
        area = float(0.5 * np.linalg.norm(np.cross(V[fixed[:, 1]] - V[fixed[:, 0]],
                                                   V[fixed[:, 2]] - V[fixed[:, 0]]), axis=1).sum())
        if abs(capped) < CAPPED_VOLUME_MIN * area ** 1.5 / (6.0 * np.sqrt(np.pi)):
            reliable = False
            reason = ("the mesh is open and its holes are too large to tell its outside from its inside "
                      "(the enclosed volume changes sign with the reference point, and is about 0 with "
                      "the holes closed)")
        elif capped < 0:
            fixed = fixed[:, ::-1].copy()
    return Orientation(fixed, reliable, reason, _n_flipped(faces, fixed))


def _capped_volume(vertices: np.ndarray, faces: np.ndarray) -> float:
    """Volume enclosed by the consistently wound ``faces`` with each boundary loop closed by a fan.

    Each boundary half-edge ``(a, b)`` adds the triangle ``(b, a, c)`` with
    ``c`` the centroid of its loop's vertices, so that every edge of the
    capped surface is used once in each direction and the volume
    (divergence theorem) does not depend on the reference point.
    """
    from .boundary import boundary_edges

    n = len(vertices)
    edges = boundary_edges(faces, n)
    volume = _signed_volumes(vertices, faces, vertices.mean(axis=0)[None, :])[0]
    if len(edges) == 0:
        return float(volume)
    import scipy.sparse as sp
    from scipy.sparse.csgraph import connected_components

    graph = sp.coo_matrix((np.ones(len(edges)), (edges[:, 0], edges[:, 1])), shape=(n, n))
    _, labels = connected_components(graph, directed=False)
    loop = labels[edges[:, 0]]
    on_loop = np.unique(edges)
    counts = np.bincount(labels[on_loop], minlength=labels.max() + 1)
    centroids = np.stack([np.bincount(labels[on_loop], weights=vertices[on_loop, c], minlength=len(counts))
                          for c in range(3)], axis=1) / np.maximum(counts, 1)[:, None]
    centre = vertices.mean(axis=0)
    a, b, c = vertices[edges[:, 1]] - centre, vertices[edges[:, 0]] - centre, centroids[loop] - centre
    volume += np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6.0
    return float(volume)


def _n_flipped(before: np.ndarray, after: np.ndarray) -> int:
    """Faces whose cyclic order changed (same vertex sets, row by row)."""
    b, a = np.asarray(before), np.asarray(after)
    same = np.zeros(len(b), dtype=bool)
    for shift in range(3):
        same |= (np.roll(b, shift, axis=1) == a).all(axis=1)
    return int((~same).sum())


def mesh_orientation(mesh: Mesh) -> Orientation:
    """:func:`orient_outward` of a :class:`~meshcorr.core.mesh.Mesh`, cached on it (the mesh is immutable).

    For a point cloud: no faces, and the reliability of its estimated normals
    (:func:`cloud_normals`).
    """
    key = ("orientation",)
    if key not in mesh.store:
        if mesh.is_cloud:
            estimate = cloud_normals(mesh)
            mesh.store.put(key, Orientation(mesh.faces, estimate.reliable, estimate.reason, 0))
        else:
            mesh.store.put(key, orient_outward(mesh.vertices, mesh.faces))
    return mesh.store[key]


def cloud_normals(mesh: Mesh):
    """:func:`meshcorr.core.normals.estimate_normals` of a point cloud, cached on it."""
    from .laplacian import vertex_areas
    from .normals import estimate_normals

    key = ("cloud_normals",)
    if key not in mesh.store:
        mesh.store.put(key, estimate_normals(mesh.vertices, vertex_areas(mesh)))
    return mesh.store[key]


def vertex_normals(vertices: np.ndarray, faces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Area-weighted unit vertex normals and lumped vertex areas.

    Parameters
    ----------
    vertices : (n, 3) float
    faces : (m, 3) int
        Consistently oriented.

    Returns
    -------
    normals : (n, 3) float
        Sum of the adjacent faces' area vectors, normalised.
    areas : (n,) float
        A third of the adjacent faces' areas (barycentric lumped mass).
    """
    v = vertices[faces]
    cross = np.cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0])  # 2 * area * unit normal
    n = len(vertices)
    normals = np.stack([np.bincount(faces.ravel(), weights=np.repeat(cross[:, c], 3), minlength=n)
                        for c in range(3)], axis=1)
    areas = np.bincount(faces.ravel(), weights=np.repeat(np.linalg.norm(cross, axis=1) / 6.0, 3), minlength=n)
    length = np.linalg.norm(normals, axis=1, keepdims=True)
    return normals / np.where(length > 0, length, 1.0), areas


def _tangent_frames(normals: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Right-handed unit tangents ``(u, v)`` with ``u x v = normal``."""
    helper = np.where(np.abs(normals[:, :1]) < 0.9, [[1.0, 0.0, 0.0]], [[0.0, 1.0, 0.0]])
    u = np.cross(helper, normals)
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    return u, np.cross(normals, u)


def oriented_normals(mesh: Mesh) -> tuple[np.ndarray, np.ndarray]:
    """Outward unit vertex normals ``(n, 3)`` and vertex areas ``(n,)``, cached on the mesh.

    A mesh: :func:`vertex_normals` of its outward-oriented faces. A point
    cloud: its estimated normals (:func:`cloud_normals`) and its Laplacian's
    vertex areas. Cached because the pipeline scores several candidate maps
    between the same two shapes.
    """
    key = ("oriented_vertex_normals",)
    if key not in mesh.store:
        if mesh.is_cloud:
            from .laplacian import vertex_areas

            normals, areas = np.array(cloud_normals(mesh).normals), np.array(vertex_areas(mesh))
        else:
            normals, areas = vertex_normals(mesh.vertices, mesh_orientation(mesh).faces)
        normals.flags.writeable = areas.flags.writeable = False
        mesh.store.put(key, (normals, areas))
    return mesh.store[key]


def _neighbourhoods(source: Mesh, n_neighbors: int, n_sample: int, random_state) -> tuple:
    """The map-independent part of :func:`orientation_score`, cached on the source mesh.

    Returns the sampled vertices ``(s,)``, their ``K`` nearest vertices
    ``(s, K)``, the neighbours' tangent coordinates ``a`` ``(s, K, 2)`` and the
    sampled vertices' areas ``(s,)``.
    """
    # Only a seeded sample is the same every time (random_state=None draws anew).
    seeded = isinstance(random_state, (int, np.integer))
    key = ("orientation_neighbourhoods", n_neighbors, n_sample, int(random_state) if seeded else None)
    if not seeded or key not in source.store:
        X = source.vertices
        src_normals, src_areas = oriented_normals(source)
        rng = np.random.default_rng(random_state)
        n1 = len(X)
        sample = np.arange(n1) if n1 <= n_sample else np.sort(rng.choice(n1, size=n_sample, replace=False))
        k = min(n_neighbors + 1, n1)
        _, nbrs = cKDTree(X).query(X[sample], k=k)
        nbrs = nbrs[:, 1:]  # drop the vertex itself
        u, v = _tangent_frames(src_normals[sample])
        dx = X[nbrs] - X[sample, None, :]
        a = np.stack([np.einsum("skc,sc->sk", dx, u), np.einsum("skc,sc->sk", dx, v)], axis=2)  # (s, K, 2)
        parts = (sample, nbrs, a, src_areas[sample])
        for array in parts:
            array.flags.writeable = False
        if not seeded:
            return parts
        source.store.put(key, parts)
    return source.store[key]


def orientation_score(source: Mesh, target: Mesh, mapping: np.ndarray, *, n_neighbors: int = 16,
                      n_sample: int = 2000, random_state: int | None = 0) -> float:
    """Fraction of the source on which a vertex map keeps the orientation.

    Parameters
    ----------
    source, target : Mesh
        Orientation is repaired internally (:func:`mesh_orientation`).
    mapping : (n1,) int
        ``mapping[i]`` is the target vertex of source vertex i.
    n_neighbors : int
        Size of the neighbourhood whose image is tested (>= 2).
    n_sample : int
        Source vertices tested (a seeded sample; all if fewer).
    random_state : int or None
        Seed of the sample.

    Returns
    -------
    score : float in [0, 1]
        Area-weighted fraction of tested vertices whose mapped neighbourhood
        keeps its orientation (module docstring); 0.5 when every tested
        neighbourhood collapses onto a single target vertex.
    """
    n_neighbors, n_sample, mapping = _checked(source, target, mapping, n_neighbors, n_sample)
    _, triple, areas = _orientation_signs(source, target, mapping, n_neighbors, n_sample, random_state)
    return _score(triple, areas)


def _checked(source: Mesh, target: Mesh, mapping, n_neighbors, n_sample) -> tuple[int, int, np.ndarray]:
    """The checked ``n_neighbors``, ``n_sample`` and map of :func:`orientation_score`."""
    n_neighbors = check_int("n_neighbors", n_neighbors, minimum=2)
    n_sample = check_int("n_sample", n_sample, minimum=1)
    mapping = np.asarray(mapping)
    if mapping.shape != (source.n_vertices,):
        raise ParameterError(f"The map must have one entry per source vertex ({source.n_vertices}). "
                             f"Got shape {mapping.shape} instead.")
    if mapping.size and (mapping.min() < 0 or mapping.max() >= target.n_vertices):
        raise ParameterError(f"The map must hold target vertex indices in [0, {target.n_vertices}). "
                             f"Got values in [{mapping.min()}, {mapping.max()}] instead.")
    return n_neighbors, n_sample, mapping


def _score(triple: np.ndarray, areas: np.ndarray) -> float:
    """:func:`orientation_score` from the triple products of :func:`_orientation_signs`."""
    w = areas * (triple != 0)
    if w.sum() == 0:
        return 0.5
    return float((w * (triple > 0)).sum() / w.sum())


def _orientation_signs(source: Mesh, target: Mesh, mapping: np.ndarray, n_neighbors: int, n_sample: int,
                       random_state) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Sampled source vertices ``(s,)``, the triple product of each one's mapped frame ``(s,)``
    (positive where the map keeps the orientation) and their areas ``(s,)``."""
    Y = target.vertices
    sample, nbrs, a, areas = _neighbourhoods(source, n_neighbors, n_sample, random_state)
    tgt_normals, _ = oriented_normals(target)
    dy = Y[mapping[nbrs]] - Y[mapping[sample], None, :]  # (s, K, 3)
    c = np.einsum("skc,skt->sct", dy, a)  # (s, 3, 2): images of u, v up to a positive factor
    triple = np.einsum("sc,sc->s", tgt_normals[mapping[sample]], np.cross(c[:, :, 0], c[:, :, 1]))
    return sample, triple, areas


def regional_orientation(source: Mesh, target: Mesh, mapping: np.ndarray, *, n_regions: int = 12,
                         n_neighbors: int = 16, n_sample: int = 2000, random_state: int | None = 0
                         ) -> np.ndarray:
    """The orientation score of a map region by region: a partly mirrored map shows up.

    A map whose legs are swapped left for right while the upper body is
    right keeps the orientation on most of the surface, so its
    :func:`orientation_score` stays high; on the swapped part it reverses
    the orientation. The sampled vertices of :func:`orientation_score` are
    split into ``n_regions`` regions (nearest of as many farthest-point
    seeds, in space), and each region is scored alone.

    Parameters
    ----------
    source, target : Mesh
    mapping : (n1,) int
    n_regions : int
    n_neighbors, n_sample, random_state
        As :func:`orientation_score`.

    Returns
    -------
    scores : (r,) float in [0, 1]
        Area-weighted fraction of each region's sampled vertices whose
        orientation is kept (0.5 where every neighbourhood collapses), in
        order of the seeds.
    """
    n_regions = check_int("n_regions", n_regions, minimum=1)
    _, triple, areas = _orientation_signs(source, target, np.asarray(mapping), n_neighbors, n_sample, random_state)
    return _regional_scores(source, triple, areas, n_regions, n_neighbors, n_sample, random_state)


def orientation_scores(source: Mesh, target: Mesh, mapping: np.ndarray, *, n_regions: int = 12,
                       n_neighbors: int = 16, n_sample: int = 2000, random_state: int | None = 0
                       ) -> tuple[float, np.ndarray]:
    """:func:`orientation_score` and :func:`regional_orientation` of one map, its frames mapped once.

    Parameters
    ----------
    source, target : Mesh
    mapping : (n1,) int
    n_regions, n_neighbors, n_sample, random_state
        As :func:`regional_orientation`.

    Returns
    -------
    score : float
        ``orientation_score(source, target, mapping, ...)``, the same value.
    regional : (r,) float
        ``regional_orientation(source, target, mapping, ...)``, the same values.
    """
    _, triple, areas, regional = _signs_by_region(source, target, mapping, n_regions, n_neighbors, n_sample,
                                                  random_state)
    return _score(triple, areas), regional


def _signs_by_region(source: Mesh, target: Mesh, mapping, n_regions, n_neighbors, n_sample, random_state
                     ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The checked inputs' :func:`_orientation_signs` ``(sample, triple, areas)`` and regional scores ``(r,)``."""
    n_neighbors, n_sample, mapping = _checked(source, target, mapping, n_neighbors, n_sample)
    n_regions = check_int("n_regions", n_regions, minimum=1)
    sample, triple, areas = _orientation_signs(source, target, mapping, n_neighbors, n_sample, random_state)
    return sample, triple, areas, _regional_scores(source, triple, areas, n_regions, n_neighbors, n_sample,
                                                   random_state)


def consistent_vertices(source: Mesh, target: Mesh, mapping: np.ndarray, *, n_regions: int = 12,
                        n_neighbors: int = 16, n_sample: int = 2000, random_state: int | None = 0) -> np.ndarray:
    """The sampled source vertices where a map keeps the orientation, in regions that keep it.

    Parameters
    ----------
    source, target : Mesh
    mapping : (n1,) int
    n_regions, n_neighbors, n_sample, random_state
        As :func:`regional_orientation`.

    Returns
    -------
    vertices : (m,) int
        The sampled vertices of :func:`orientation_score` whose own mapped
        neighbourhood keeps the orientation (triple product > 0) and whose
        region's score (:func:`regional_orientation`) is at least 0.5: the
        part of a partly mirrored map that is not mirrored
        (:mod:`meshcorr.choice.repair`).
    """
    sample, triple, _, regional = _signs_by_region(source, target, mapping, n_regions, n_neighbors, n_sample,
                                                   random_state)
    region, _ = _regions(source, n_regions, n_neighbors, n_sample, random_state)
    return sample[(triple > 0) & (regional[region] >= 0.5)]


def _regions(source: Mesh, n_regions: int, n_neighbors: int, n_sample: int, random_state) -> tuple[np.ndarray, int]:
    """The region of each sampled vertex of :func:`_neighbourhoods` ``(s,)`` and the region count.

    Depends on the source only: cached on it for a seeded sample, like :func:`_neighbourhoods`.
    """
    seeded = isinstance(random_state, (int, np.integer))
    key = ("orientation_regions", n_regions, n_neighbors, n_sample, int(random_state) if seeded else None)
    if seeded and key in source.store:
        return source.store[key]
    sample = _neighbourhoods(source, n_neighbors, n_sample, random_state)[0]
    points = source.vertices[sample]
    seeds = farthest_point_sampling(lambda i: np.linalg.norm(points - points[i], axis=1), len(points),
                                    min(n_regions, len(points)), start=0).indices
    region = cKDTree(points[seeds]).query(points)[1]
    region.flags.writeable = False
    parts = (region, int(len(seeds)))
    if seeded:
        source.store.put(key, parts)
    return parts


def _regional_scores(source: Mesh, triple: np.ndarray, areas: np.ndarray, n_regions: int, n_neighbors: int,
                     n_sample: int, random_state) -> np.ndarray:
    """:func:`regional_orientation` from the triple products of :func:`_orientation_signs`."""
    region, n_seeds = _regions(source, n_regions, n_neighbors, n_sample, random_state)
    w = areas * (triple != 0)
    kept = np.bincount(region, weights=w * (triple > 0), minlength=n_seeds)
    total = np.bincount(region, weights=w, minlength=n_seeds)
    return np.where(total > 0, kept / np.maximum(total, 1e-300), 0.5)
