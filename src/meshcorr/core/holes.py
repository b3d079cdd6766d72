"""Holes closed before matching, and the map brought back to the input's vertices.

A scan has holes where the sensor saw nothing, and a model may have a few
missing triangles. Every intrinsic quantity of the pipeline then changes
near them: geodesic distances detour around a hole, the Laplace-Beltrami
eigenfunctions get a boundary condition there, a hole on a tip moves the
shape's extremities, and two shapes with holes in different places no
longer look alike to the spectral steps.

Whole-shape matching (the default) therefore closes each hole first: every
boundary loop that is a simple cycle gets one new vertex at the centroid of
its vertices and a fan of triangles joining it to the loop's edges. For a
boundary half-edge :math:`(a, b)` (in its face's winding) the new face is
:math:`(b, a, c)`, so the caps keep the winding of the surface and the
filled mesh is a closed 2-manifold wherever the loops were simple. This is
the coarsest hole filling (Liepa, "Filling holes in meshes", SGP 2003, starts
from such a patch and then refines and fairs it); the pipeline only needs
the topology and roughly the area back, not a faired surface, so the
refinement is left out. Measured on 36 TOSCA and Sumner pairs with 5-10
holes of 0.5 % of the area in both meshes (``benchmarks/RESULTS-scans.md``):
mean error 0.0241 without filling, 0.0190 with it, against 0.0186 for the
meshes without holes; filling only the loops up to 0.6 x sqrt(area) long
gave 0.0272 (the two meshes then differ in which holes stay open).

The cap vertices are appended after the input's vertices: they take the
indices ``n_input, n_input + 1, ...`` of the extended numbering
(:attr:`meshcorr.core.mesh.Mesh.n_caps`), so landmarks and every per-vertex
array of the input keep their meaning. :func:`restrict` drops them from a
result: a source cap vertex is not reported, and a source vertex sent to a
target cap vertex is sent to the loop vertex nearest that cap's centre.

Not filled: point clouds (no faces), loops that touch themselves or another
loop (a vertex with several boundary edges out), loops whose centre lies on
the line of one of their edges (a fan triangle without area), the partial mode
(:mod:`meshcorr.pipeline.partial`: the boundary of a part is information, not a
hole) and one-to-one maps (the vertex counts must stay the input's).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from .boundary import enclosed_areas, mesh_boundary
from .mesh import Mesh

#: A closed loop that encloses at least this share of the mesh's area (:func:`meshcorr.core.boundary.enclosed_areas`)
#: looks like a cut rather than a hole (:func:`large_closed_loops`). Measured on TOSCA 5k
#: (``benchmarks/RESULTS-partial.md``): holes of 0.5-2 % of the area enclose at most 0.021, plane cuts
#: to 70 % of the area at least 0.03 in 90 % of the cases.
LARGE_HOLE = 0.03


def fills(fill_holes: bool, *, partial: str | None, bijective: bool) -> bool:
    """Whether a match with these options closes holes: asked for, whole shapes, not one-to-one."""
    return bool(fill_holes) and partial is None and not bijective


def fill_holes(mesh: Mesh) -> Mesh:
    """``mesh`` with every simple boundary loop closed by a fan around its centroid (module docstring).

    Parameters
    ----------
    mesh : Mesh
        A validated triangle mesh (a point cloud or a closed mesh comes back unchanged).

    Returns
    -------
    filled : Mesh
        ``n + c`` vertices for ``c`` filled loops: the input's ``n`` first,
        then one centre per loop; the input's faces first, then each loop's
        fan, one face per boundary edge. ``filled.kept`` extends
        ``mesh.kept`` by ``mesh.n_original + arange(c)``, ``filled.n_original``
        is ``mesh.n_original + c`` and ``filled.n_caps`` is
        ``mesh.n_caps + c``. The same object when nothing is filled.
    """
    if mesh.is_cloud:
        return mesh
    boundary = mesh_boundary(mesh)
    if boundary.n_loops == 0:
        return mesh
    edges, loop = boundary.edges, boundary.loop
    simple, centres = _closable(mesh)
    filled = np.flatnonzero(simple)
    if len(filled) == 0:
        return mesh
    centre_of = np.full(boundary.n_loops, -1, dtype=np.int64)
    centre_of[filled] = mesh.n_vertices + np.arange(len(filled))
    chosen = simple[loop]
    corners = edges[chosen]
    centres = centres[filled]
    fans = np.column_stack([corners[:, 1], corners[:, 0], centre_of[loop[chosen]]])
    n_new = len(filled)
    return Mesh(np.vstack([mesh.vertices, centres]), np.vstack([mesh.faces, fans]), name=mesh.name,
                kept=np.concatenate([mesh.kept, mesh.n_original + np.arange(n_new)]),
                n_original=mesh.n_original + n_new, n_caps=mesh.n_caps + n_new)


def _closable(mesh: Mesh) -> tuple[np.ndarray, np.ndarray]:
    """``(n_loops,)`` bool: the loops :func:`fill_holes` closes, and ``(n_loops, 3)``: their centroids."""
    boundary = mesh_boundary(mesh)
    edges, loop = boundary.edges, boundary.loop
    # A loop is simple when each of its vertices starts exactly one of its edges (and so ends one).
    starts = np.bincount(edges[:, 0], minlength=mesh.n_vertices)
    simple = np.ones(boundary.n_loops, dtype=bool)
    simple[np.unique(loop[starts[edges[:, 0]] != 1])] = False
    simple &= np.bincount(loop, minlength=boundary.n_loops) >= 3
    sums = np.zeros((boundary.n_loops, 3))
    np.add.at(sums, loop, mesh.vertices[edges[:, 0]])
    centres = sums / np.bincount(loop, minlength=boundary.n_loops)[:, None]
    # A fan triangle without area (the centre on the line of a rim edge, e.g. a rim vertex itself)
    # would break the cotangent weights: such a loop stays open.
    simple[np.unique(loop[_flat(mesh.vertices[edges[:, 0]], mesh.vertices[edges[:, 1]], centres[loop])])] = False
    return simple, centres


def _flat(a: np.ndarray, b: np.ndarray, c: np.ndarray, *, tolerance: float = 1e-6) -> np.ndarray:
    """``(m,)`` bool: triangles ``(a, b, c)`` whose area is below ``tolerance`` x their squared side lengths."""
    doubled = np.linalg.norm(np.cross(b - a, c - a), axis=1)
    scale = ((b - a) ** 2).sum(axis=1) + ((c - a) ** 2).sum(axis=1) + ((c - b) ** 2).sum(axis=1)
    return doubled <= tolerance * scale


def unfilled(mesh: Mesh) -> Mesh:
    """The mesh :func:`fill_holes` was given: ``mesh`` without its cap vertices and their faces.

    Parameters
    ----------
    mesh : Mesh

    Returns
    -------
    mesh : Mesh
        The same object when it has no caps.
    """
    if mesh.n_caps == 0:
        return mesh
    n = mesh.n_vertices - mesh.n_caps
    faces = mesh.faces[(mesh.faces < n).all(axis=1)]
    return Mesh(mesh.vertices[:n], faces, name=mesh.name, kept=mesh.kept[:n], n_original=mesh.n_input)


def large_closed_loops(mesh: Mesh) -> tuple[np.ndarray, np.ndarray]:
    """The loops :func:`fill_holes` closed on ``mesh`` that look like a cut rather than a hole.

    A hole of a whole shape (a missing patch of a scan, a few missing
    triangles) encloses a small share of the area; a plane cut, which
    :func:`fill_holes` closes as well, encloses a cross-section of the body.
    The loops whose enclosed area (:func:`meshcorr.core.boundary.enclosed_areas`)
    is at least :data:`LARGE_HOLE` of the area are reported (the loop's length
    is no such measure: on a coarse mesh a loop zigzags along the edges, and
    a hole of 0.5 % of the area can leave one as long as a cut's).

    Parameters
    ----------
    mesh : Mesh
        A mesh from :func:`fill_holes` (or any mesh: without caps, nothing was closed).

    Returns
    -------
    lengths : (c,) float
        Each such loop's length divided by sqrt(the area of the mesh as given), largest enclosure first.
    enclosed : (c,) float
        The share of that area each encloses.
    """
    if mesh.n_caps == 0:
        return np.zeros(0), np.zeros(0)
    given = unfilled(mesh)
    boundary = mesh_boundary(given)
    enclosed = enclosed_areas(given)
    large = np.flatnonzero(_closable(given)[0] & (enclosed >= LARGE_HOLE))
    large = large[np.argsort(-enclosed[large], kind="stable")]
    return boundary.lengths[large] / np.sqrt(given.area), enclosed[large]


def cap_targets(mesh: Mesh) -> np.ndarray:
    """``(n_caps,)`` int: for each cap vertex, the input index of the nearest vertex of its loop.

    Parameters
    ----------
    mesh : Mesh
        A mesh from :func:`fill_holes`.
    """
    n = mesh.n_vertices - mesh.n_caps
    fans = mesh.faces[mesh.faces[:, 2] >= n]  # fill_holes puts each centre third
    distance = np.linalg.norm(mesh.vertices[fans[:, 0]] - mesh.vertices[fans[:, 2]], axis=1)
    nearest = np.full(mesh.n_caps, -1, dtype=np.int64)
    best = np.full(mesh.n_caps, np.inf)
    for corner, cap, d in zip(fans[:, 0], fans[:, 2] - n, distance):
        if d < best[cap]:
            best[cap], nearest[cap] = d, corner
    return mesh.kept[nearest]


def restrict_map(mapping: np.ndarray | None, source: Mesh, target: Mesh) -> np.ndarray | None:
    """A map in the filled numbering as a map of the input's vertices onto the input's vertices.

    Parameters
    ----------
    mapping : (source.n_original,) int or None
        Target vertex (extended numbering, -1 for none) of each source vertex
        (extended numbering).
    source, target : Mesh
        The filled meshes.

    Returns
    -------
    mapping : (source.n_input,) int or None
        Cap rows dropped; an image on a target cap replaced by the input
        vertex of its loop nearest the cap's centre (:func:`cap_targets`).
    """
    if mapping is None:
        return None
    mapping = np.array(mapping[:source.n_input], dtype=np.int64)
    on_cap = mapping >= target.n_input
    if on_cap.any():
        mapping[on_cap] = cap_targets(target)[mapping[on_cap] - target.n_input]
    return mapping


def restrict(result, source: Mesh, target: Mesh):
    """A :class:`~meshcorr.maps.result.Correspondence` between filled meshes, on the input's vertices.

    Parameters
    ----------
    result : Correspondence
        Of :func:`meshcorr.match` on the filled ``source`` and ``target``.
    source, target : Mesh
        The filled meshes.

    Returns
    -------
    result : Correspondence
        ``map``, ``alternative_map`` and ``cost`` over the input's source
        vertices (:func:`restrict_map`); the vertex lists, embeddings and
        anchors without cap vertices; ``source`` and ``target`` the meshes
        as given (:func:`unfilled`); ``params["holes_closed"]`` the number of
        holes closed on each side. Candidate summaries and timings stay.
    """
    if source.n_caps == 0 and target.n_caps == 0:
        return result
    source_rows = source.kept < source.n_input  # local rows that are input vertices
    target_rows = target.kept < target.n_input
    anchors = result.anchors
    if anchors is not None:
        anchors = anchors[(anchors[:, 0] < source.n_input) & (anchors[:, 1] < target.n_input)]
    return dataclasses.replace(
        result, map=restrict_map(result.map, source, target),
        alternative_map=restrict_map(result.alternative_map, source, target),
        cost=None if result.cost is None else result.cost[:source.n_input],
        source_vertices=_rows(result.source_vertices, source_rows),
        target_vertices=_rows(result.target_vertices, target_rows),
        source_embedding=_rows(result.source_embedding, source_rows),
        target_embedding=_rows(result.target_embedding, target_rows),
        aligned_target_embedding=_rows(result.aligned_target_embedding, target_rows),
        anchors=anchors, source=unfilled(source), target=unfilled(target),
        params=dict(result.params, holes_closed={"source": source.n_caps, "target": target.n_caps}))


def _rows(array: np.ndarray | None, keep: np.ndarray) -> np.ndarray | None:
    return None if array is None else np.asarray(array)[keep]
