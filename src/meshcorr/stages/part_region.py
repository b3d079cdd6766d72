"""The region of the whole that a part -> whole map covers, its area share, and the map turned round.

A vertex map from a part :math:`P` into the whole :math:`W` is not onto:
its images :math:`T(P)` are scattered over the region the part covers
(docs/method.md, "Partial shapes", step 7). :func:`matched_region` joins
them by a morphological closing along the surface (multi-source Dijkstra on
the edge graph, :func:`edge_graph`),

.. math::

    R = \\left( \\{ j : d(j, T(P)) \\le \\rho + c \\} \\ominus c \\right)
        \\cup \\{ j : d(j, T(P)) \\le \\rho \\},

the reach :math:`\\rho` 1.5 x the coarser of the two vertex spacings, the
part's in the whole's units (:func:`region_reach`), and the closing
:math:`c` = :data:`REGION_CLOSING` x sqrt(area(W)) (:func:`part_region`).
Its area share :math:`r = \\operatorname{area}(R) / \\operatorname{area}(W)`
(:func:`area_fraction`, vertex areas) is the slope of the part's
functional map used by the refinements (:func:`matched_share`), and
:func:`invert_part_map` turns the map round on :math:`R`.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import dijkstra
from scipy.spatial import cKDTree

from ..core.mesh import Mesh
from ..core.orientation import vertex_normals

#: Radius of the closing that joins the matched region, x sqrt(area of the whole).
REGION_CLOSING = 0.03


def edge_graph(mesh: Mesh) -> sp.csr_matrix:
    """``(n, n)`` sparse: the edge lengths of ``mesh``, symmetric, kept in its store."""
    key = ("edge_graph",)
    if key not in mesh.store:
        f = mesh.faces
        e = np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]])
        lengths = np.linalg.norm(mesh.vertices[e[:, 0]] - mesh.vertices[e[:, 1]], axis=1)
        n = mesh.n_vertices
        graph = sp.coo_matrix((lengths, (e[:, 0], e[:, 1])), shape=(n, n)).tocsr()
        mesh.store.put(key, graph.maximum(graph.T).tocsr())
    return mesh.store[key]


def mean_edge_length(mesh: Mesh) -> float:
    """Mean edge length of ``mesh``."""
    return float(edge_graph(mesh).data.mean())


def matched_region(whole: Mesh, images: np.ndarray, *, reach: float, closing: float) -> np.ndarray:
    """``(n_whole,)`` bool: the whole's vertices that the map reaches, joined by a closing.

    The vertices within ``reach`` (along the edges, multi-source Dijkstra) of
    an image are dilated by ``closing`` and eroded by as much again: gaps
    narrower than about twice ``closing`` between images are filled (a
    vertex map is not onto), the outline does not grow.

    Parameters
    ----------
    whole : Mesh
    images : (p,) int
        Whole vertices the part maps to.
    reach, closing : float
        Lengths in the whole's units.
    """
    graph = edge_graph(whole)
    near = dijkstra(graph, directed=False, indices=np.unique(images), min_only=True, limit=reach + closing)
    dilated = np.isfinite(near)
    outside = np.flatnonzero(~dilated)
    if len(outside) == 0:
        return dilated
    back = dijkstra(graph, directed=False, indices=outside, min_only=True, limit=closing)
    return dilated & ~np.isfinite(back) | (np.isfinite(near) & (near <= reach))


def part_region(part: Mesh, whole: Mesh, mapping: np.ndarray, scale: float) -> np.ndarray:
    """:func:`matched_region` of a part -> whole map with the module's reach and closing."""
    return matched_region(whole, mapping, reach=region_reach(part, whole, scale),
                          closing=REGION_CLOSING * np.sqrt(whole.area))


def region_reach(part: Mesh, whole: Mesh, scale: float) -> float:
    """How far around an image the whole counts as reached: 1.5 x the coarser of the two vertex spacings.

    ``scale`` is whole length per part length (the part's mean edge length is taken in the whole's units).
    """
    return 1.5 * max(mean_edge_length(whole), scale * mean_edge_length(part))


def matched_share(part: Mesh, whole: Mesh, mapping: np.ndarray, scale: float) -> tuple[np.ndarray, float]:
    """The region of the whole a map reaches (:func:`part_region`) and its area fraction r, clipped to
    [0.2, 1]: the region and r of the refinements (:func:`meshcorr.stages.partial_zoomout.partial_zoomout`,
    the part's smooth shells)."""
    region = part_region(part, whole, mapping, scale)
    return region, float(np.clip(area_fraction(whole, region), 0.2, 1.0))


def area_fraction(mesh: Mesh, mask: np.ndarray) -> float:
    """Area of the vertices in ``mask`` (``(n,)`` bool) over the mesh's area, with the lumped vertex areas of
    :func:`meshcorr.core.orientation.vertex_normals`."""
    _, areas = vertex_normals(mesh.vertices, mesh.faces)
    return float(areas[mask].sum() / areas.sum())


def invert_part_map(whole: Mesh, mapping: np.ndarray, region: np.ndarray) -> np.ndarray:
    """A whole -> part map from a part -> whole one, defined on the matched region only.

    Parameters
    ----------
    whole : Mesh
    mapping : (n_part,) int
        Whole vertex of each part vertex.
    region : (n_whole,) bool
        The matched region (:func:`matched_region`).

    Returns
    -------
    inverse : (n_whole,) int
        For a vertex of the region, the part vertex whose image is nearest
        to it in space (itself where it is an image); -1 outside.
    """
    inverse = np.full(whole.n_vertices, -1, dtype=np.int64)
    inside = np.flatnonzero(region)
    if len(inside):
        inverse[inside] = cKDTree(whole.vertices[mapping]).query(whole.vertices[inside])[1]
    return inverse
