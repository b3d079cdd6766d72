"""Surface orientation of one shape: consistent outward winding, outward normals and whether they are reliable.

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


The orientation a vertex map keeps (its score, used to tell a map from its
mirror image) is :mod:`meshcorr.core.map_orientation`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

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


def tangent_frames(normals: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
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
