"""Outward normals of a point cloud, estimated and checked.

A mesh's triangles give its normals and, once their winding is made
consistent, its outside (:mod:`meshcorr.orientation`). A cloud has neither;
the pipeline needs both (the orientation score that tells a map from its
mirror image, the sign of the curvature), so they are estimated here in the
three steps of Hoppe, DeRose, Duchamp, McDonald & Stuetzle, "Surface
reconstruction from unorganized points" (SIGGRAPH 1992), then checked:

1. **Tangent planes.** The normal line at point :math:`i` is the
   eigenvector of the smallest eigenvalue of the covariance of its
   :data:`N_NORMAL_NEIGHBORS` nearest points (principal component analysis).
2. **Consistent orientation.** Neighbouring normals should point the same
   way. Over the cloud's neighbour graph (:func:`meshcorr.pointcloud.edges`,
   Hoppe's "Riemannian graph": nearest neighbours and a spanning tree) with
   weights :math:`1 - |n_i \\cdot n_j| + |n_i \\cdot e_{ij}| + |n_j \\cdot e_{ij}|`
   (:math:`e_{ij}` the unit offset between the points), a minimum spanning
   tree is walked breadth-first from one point and each normal is flipped to
   agree with its parent's. Hoppe's weight, the first two terms, prefers
   nearly parallel planes, so orientation propagates along smooth parts
   first and across creases last; the offset terms, added here, keep it from
   jumping between the two sides of a thin part (their planes are parallel,
   but the offset between them is along the normals). Measured on the
   vertices of TOSCA cat0, michael0, horse0 and centaur0 (5000 points
   each): 3-10 % of the points get a normal opposite to the mesh's (in thin
   parts: ears, hooves, fingers), 4-13 % with Hoppe's weight alone.
3. **Outward.** By the divergence theorem, the volume enclosed by a closed
   surface is :math:`V = \\frac{1}{3} \\sum_i a_i (x_i - o) \\cdot n_i` for
   outward normals :math:`n_i`, vertex areas :math:`a_i` and any origin
   :math:`o`; all normals are flipped if it is negative from the centroid.

The estimate is called **unreliable** (the same flag and warning as a mesh's
orientation, :attr:`meshcorr.orientation.Orientation.reliable`) when

- more than :data:`MAX_DISAGREEMENT` of the neighbour pairs that lie side
  by side on the surface (their offset at most 60 degrees off the tangent
  planes) have normals pointing opposite ways after step 2: the propagation
  failed somewhere (noise larger than the spacing, parts thinner than the
  neighbourhoods), or
- the cloud is open (one side of a scan, a flat sheet, large holes), so its
  inside cannot be told from its outside: the area-weighted sum of the
  normals, :math:`|\\sum_i a_i n_i| / \\sum_i a_i`, which is 0 for a closed
  surface (the divergence theorem again, for a constant field), exceeds
  :data:`MAX_OPENNESS`, or the enclosed volume changes sign between the
  centroid and the corners of the bounding box (the mesh's test). Measured:
  0.01-0.04 on TOSCA shapes' vertices, with or without noise of 1 % of the
  bounding box; 0.2 for a sphere without a fifth of its area, 0.5 for a
  hemisphere.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import breadth_first_order, minimum_spanning_tree
from scipy.spatial import cKDTree

from .pointcloud import edges

__all__ = ["CloudNormals", "estimate_normals", "MAX_DISAGREEMENT", "MAX_OPENNESS", "N_NORMAL_NEIGHBORS"]

#: Neighbours whose covariance gives a point's tangent plane.
N_NORMAL_NEIGHBORS = 16
#: Weight of the offset terms in the propagation's spanning tree (module docstring).
WEIGHT_ACROSS = 1.0
#: Largest share of side-by-side neighbour pairs whose oriented normals may disagree.
MAX_DISAGREEMENT = 0.05
#: Largest area-weighted normal sum, as a fraction of the area, of a cloud called closed (module docstring).
MAX_OPENNESS = 0.15
#: A neighbour pair lies "side by side" when its offset is within this cosine of the tangent planes.
_SIDE_BY_SIDE = 0.5


@dataclass(frozen=True)
class CloudNormals:
    """The outcome of :func:`estimate_normals`.

    Attributes
    ----------
    normals : (n, 3) float
        Unit normals, oriented consistently and outwards where possible.
    reliable : bool
        Whether the orientation can be trusted (module docstring).
    reason : str
        Why not, when ``reliable`` is False; empty otherwise.
    disagreement : float
        Share of side-by-side neighbour pairs whose normals point opposite ways.
    """

    normals: np.ndarray
    reliable: bool
    reason: str
    disagreement: float


def _tangent_normals(points: np.ndarray, k: int) -> np.ndarray:
    """Step 1: unit normals (unoriented) by PCA of each point's ``k`` nearest points, ``(n, 3)``."""
    _, index = cKDTree(points).query(points, k=min(k + 1, len(points)))
    local = points[index] - points[index].mean(axis=1, keepdims=True)  # (n, k + 1, 3)
    covariance = np.einsum("nki,nkj->nij", local, local)
    _, vectors = np.linalg.eigh(covariance)  # ascending eigenvalues
    return np.ascontiguousarray(vectors[:, :, 0])


def _propagate(points: np.ndarray, normals: np.ndarray, pairs: np.ndarray) -> np.ndarray:
    """Step 2: flip normals to agree along a minimum spanning tree (module docstring)."""
    n = len(normals)
    i, j = pairs[:, 0], pairs[:, 1]
    dots = np.einsum("ij,ij->i", normals[i], normals[j])
    offset = points[j] - points[i]
    offset /= np.linalg.norm(offset, axis=1, keepdims=True)
    across = np.abs(np.einsum("ij,ij->i", offset, normals[i])) + np.abs(np.einsum("ij,ij->i", offset, normals[j]))
    # Weights must be positive: csgraph reads an explicit zero as "no edge".
    weight = 1.0 - np.abs(dots) + WEIGHT_ACROSS * across + 1e-9
    graph = sp.coo_matrix((weight, (pairs[:, 0], pairs[:, 1])), shape=(n, n)).tocsr()
    tree = minimum_spanning_tree(graph)
    order, parent = breadth_first_order(tree, 0, directed=False, return_predecessors=True)
    # A walk down the tree (a loop: each sign depends on the parent's, already set).
    agrees = np.einsum("ij,ij->i", normals[order[1:]], normals[parent[order[1:]]]) >= 0
    sign = np.ones(n)
    for child, parent_of, same in zip(order[1:].tolist(), parent[order[1:]].tolist(), agrees.tolist()):
        sign[child] = sign[parent_of] if same else -sign[parent_of]
    return normals * sign[:, None]


def _enclosed_volumes(points: np.ndarray, normals: np.ndarray, areas: np.ndarray,
                      origins: np.ndarray) -> np.ndarray:
    """:math:`\\frac{1}{3} \\sum_i a_i (x_i - o) \\cdot n_i` for each origin ``(o, 3)`` (divergence theorem)."""
    centre = points.mean(axis=0)
    flux = areas[:, None] * normals
    volume = np.einsum("ij,ij->", points - centre, flux)
    return (volume - (np.asarray(origins) - centre) @ flux.sum(axis=0)) / 3.0


def _disagreement(points: np.ndarray, normals: np.ndarray, pairs: np.ndarray) -> float:
    """Share of side-by-side neighbour pairs whose normals point opposite ways (module docstring)."""
    i, j = pairs[:, 0], pairs[:, 1]
    offset = points[j] - points[i]
    length = np.linalg.norm(offset, axis=1)
    side = ((np.abs(np.einsum("ij,ij->i", offset, normals[i])) <= _SIDE_BY_SIDE * length)
            & (np.abs(np.einsum("ij,ij->i", offset, normals[j])) <= _SIDE_BY_SIDE * length))
    if not side.any():
        return 1.0
    return float(np.mean(np.einsum("ij,ij->i", normals[i[side]], normals[j[side]]) < 0))


def estimate_normals(points: np.ndarray, areas: np.ndarray, *,
                     n_neighbors: int = N_NORMAL_NEIGHBORS) -> CloudNormals:
    """Consistently oriented, outward unit normals of a point cloud, and whether to trust them.

    Parameters
    ----------
    points : (n, 3) float
        Distinct points of one connected cloud (:func:`meshcorr.pointcloud.validate_cloud`).
    areas : (n,) float
        Vertex areas :math:`a_i` (:func:`meshcorr.laplacian.vertex_areas`), for the enclosed volume.
    n_neighbors : int
        Neighbours of each tangent plane.

    Returns
    -------
    estimate : CloudNormals
        Normals, the reliability verdict and the share of disagreeing neighbours
        (module docstring).
    """
    points = np.asarray(points, dtype=np.float64)
    areas = np.asarray(areas, dtype=np.float64)
    pairs = edges(points, np.zeros((0, 3), dtype=np.int64))
    normals = _propagate(points, _tangent_normals(points, n_neighbors), pairs)
    lo, hi = points.min(axis=0), points.max(axis=0)
    origins = [points.mean(axis=0)] + [np.where(np.array(c, dtype=bool), hi, lo) for c in np.ndindex(2, 2, 2)]
    volumes = _enclosed_volumes(points, normals, areas, np.array(origins))
    if volumes[0] < 0:
        normals, volumes = -normals, -volumes
    normals.flags.writeable = False
    disagreement = _disagreement(points, normals, pairs)
    openness = float(np.linalg.norm(areas @ normals) / areas.sum())
    reason = ""
    if disagreement > MAX_DISAGREEMENT:
        reason = (f"its normals could not be oriented consistently ({100 * disagreement:.0f} % of neighbouring "
                  "points have opposite normals: noise larger than the point spacing, or parts thinner than "
                  "the neighbourhoods)")
    elif openness > MAX_OPENNESS or not (volumes > 0).all():
        reason = ("the point cloud is open (one side of a scan, a flat sheet or large holes), so its outside "
                  f"cannot be told from its inside (its area-weighted normals sum to {100 * openness:.0f} % of "
                  "its area, 0 for a closed surface)")
    return CloudNormals(normals, not reason, reason, disagreement)
