"""Precise maps: each source vertex sent to a point on a target triangle.

A vertex map can only land on target vertices; a *precise map* sends
source vertex i to a point :math:`p_i = \\sum_k w_{ik} v_{f_i, k}` of target
triangle :math:`f_i`, barycentric weights :math:`w_i \\ge 0` summing to 1.
As in pyFM's precise map and in the spectral projection of Ezuz &
Ben-Chen ("Deblurring and denoising of maps between shapes", SGP 2017),
the point is found in the spectral domain: the functional map of the vertex
map, :math:`C = \\Phi_S^\\top M_S \\Phi_T[T]` (:mod:`meshcorr.spectral.fmap`), gives each
source vertex a target-side spectral position :math:`q_i = (\\Phi_S C)_i`,
and :math:`p_i` is the point of the target surface embedded by
:math:`\\Phi_T` (linear on each triangle) nearest to it,

.. math::

    (f_i, w_i) = \\arg\\min_{f,\\; w \\in \\Delta^2}
    \\Big\\lVert q_i - \\sum_{k=1}^3 w_k \\, \\Phi_T[f_k] \\Big\\rVert .

The search covers the triangles around the ``n_nearest`` target vertices
nearest to :math:`q_i`. Where the map is exact (a re-indexed copy)
:math:`q_i` is a row of :math:`\\Phi_T` and the weights are one-hot; where
the true point lies inside a triangle (a finer source), :math:`q_i`, a
band-limited interpolation, falls between the corners' rows.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

from ..runtime.checks import check_int
from ..errors import MeshError, ParameterError
from ..spectral.fmap import functional_map
from ..core.mesh import Mesh

__all__ = ["PreciseMap", "precise_map", "project_to_triangles"]


@dataclass(frozen=True)
class PreciseMap:
    """Source vertices mapped to points on target triangles.

    Attributes
    ----------
    faces : (n_source,) int
        Target triangle of each source vertex, a row of ``target_faces``; -1 where unmapped.
    weights : (n_source, 3) float
        Barycentric weights of the triangle's corners (>= 0, rows sum to 1; NaN where unmapped).
    target_faces : (m, 3) int
        The target's triangles, in the target's input vertex numbering.
    """

    faces: np.ndarray
    weights: np.ndarray
    target_faces: np.ndarray

    @property
    def corners(self) -> np.ndarray:
        """``(n_source, 3)`` int: target vertices of each source vertex's triangle (-1 where unmapped)."""
        out = self.target_faces[np.maximum(self.faces, 0)]
        out[self.faces < 0] = -1
        return out

    def vertex_map(self) -> np.ndarray:
        """``(n_source,)`` int: the corner with the largest weight (-1 where unmapped)."""
        best = np.argmax(np.nan_to_num(self.weights, nan=0.0), axis=1)
        out = self.corners[np.arange(len(self.faces)), best]
        return np.where(self.faces >= 0, out, -1)

    def interpolate(self, values) -> np.ndarray:
        """Barycentric interpolation of per-vertex target values at the mapped points.

        Parameters
        ----------
        values : (n_target,) or (n_target, c) float
            E.g. positions (giving the mapped points), UV coordinates, colours.

        Returns
        -------
        interpolated : (n_source,) or (n_source, c) float
            :math:`\\sum_k w_{ik} \\, \\text{values}[f_{ik}]`; NaN where unmapped.
        """
        try:
            values = np.asarray(values, dtype=np.float64)
        except (TypeError, ValueError):
            raise ParameterError("interpolate needs numbers: one value (or row) per target vertex.") from None
        needed = int(self.target_faces.max()) + 1 if self.target_faces.size else 0
        if values.ndim not in (1, 2) or len(values) < needed:
            raise ParameterError(f"interpolate needs one value (or row) per target vertex, at least {needed} (the "
                                 f"target's triangles name vertex {needed - 1}); got shape {values.shape}.")
        corner_values = values[np.maximum(self.corners, 0)]  # (n, 3, ...)
        weights = self.weights.reshape(self.weights.shape + (1,) * (values.ndim - 1))
        return np.sum(weights * corner_values, axis=1)

    def points(self, target_vertices) -> np.ndarray:
        """``(n_source, 3)`` float: the mapped points on the target surface."""
        return self.interpolate(target_vertices)


def project_to_triangles(q: np.ndarray, a: np.ndarray, b: np.ndarray, c: np.ndarray
                         ) -> tuple[np.ndarray, np.ndarray]:
    """Nearest points of triangles ``(a, b, c)`` to points ``q``, in any dimension.

    Parameters
    ----------
    q, a, b, c : (p, d) float
        Query points and triangle corners, row by row.

    Returns
    -------
    weights : (p, 3) float
        Barycentric weights of the nearest point (>= 0, sum 1).
    distance2 : (p,) float
        Its squared distance to ``q``.

    Notes
    -----
    The minimiser of :math:`\\lVert a + s e_0 + t e_1 - q \\rVert^2`,
    :math:`e_0 = b - a`, :math:`e_1 = c - a`, on the simplex is either the
    unconstrained solution (when it lies inside) or the nearest point of one
    of the three edges; all four are computed and the nearest kept.
    """
    e0, e1, d = b - a, c - a, q - a
    g00, g01, g11 = (np.einsum("ij,ij->i", x, y) for x, y in ((e0, e0), (e0, e1), (e1, e1)))
    r0, r1 = np.einsum("ij,ij->i", d, e0), np.einsum("ij,ij->i", d, e1)
    det = g00 * g11 - g01 * g01
    with np.errstate(divide="ignore", invalid="ignore"):
        s_in, t_in = (g11 * r0 - g01 * r1) / det, (g00 * r1 - g01 * r0) / det
        inside = (det > 1e-14 * np.maximum(g00 * g11, 1e-300)) & (s_in >= 0) & (t_in >= 0) & (s_in + t_in <= 1)
        s_ab = np.clip(r0 / g00, 0.0, 1.0)
        t_ac = np.clip(r1 / g11, 0.0, 1.0)
        ebc = c - b
        u_bc = np.clip(np.einsum("ij,ij->i", q - b, ebc) / np.einsum("ij,ij->i", ebc, ebc), 0.0, 1.0)
    # (s, t): weights of b and c for the four candidates (inside, edges ab, ac, bc)
    s = np.stack([np.where(inside, s_in, 0.0), np.nan_to_num(s_ab), np.zeros_like(r0), 1.0 - np.nan_to_num(u_bc)],
                 axis=1)
    t = np.stack([np.where(inside, t_in, 0.0), np.zeros_like(r0), np.nan_to_num(t_ac), np.nan_to_num(u_bc)],
                 axis=1)
    # |d - s e0 - t e1|^2 from the Gram entries: no (p, 4, dim) array
    dd = np.einsum("ij,ij->i", d, d)[:, None]
    distance2 = (dd - 2 * s * r0[:, None] - 2 * t * r1[:, None] + s * s * g00[:, None]
                 + 2 * s * t * g01[:, None] + t * t * g11[:, None])
    distance2 = np.maximum(distance2, 0.0)
    distance2[:, 0] = np.where(inside, distance2[:, 0], np.inf)
    best = np.argmin(distance2, axis=1)
    rows = np.arange(len(q))
    s, t = s[rows, best], t[rows, best]
    return np.stack([1.0 - s - t, s, t], axis=1), distance2[rows, best]


def _vertex_faces(faces: np.ndarray, n_vertices: int) -> tuple[np.ndarray, np.ndarray]:
    """CSR incidence: faces around vertex v are ``order[start[v]:start[v + 1]]``."""
    flat = faces.reshape(-1)
    order = np.argsort(flat, kind="stable") // 3
    start = np.concatenate([[0], np.cumsum(np.bincount(flat, minlength=n_vertices))])
    return order, start


def precise_map(source: Mesh, target: Mesh, mapping: np.ndarray, *, k: int = 30, n_nearest: int = 4,
                random_state: int | None = 0) -> PreciseMap:
    """The precise map of a vertex map (module docstring).

    Parameters
    ----------
    source, target : Mesh
        The meshes the map was computed on.
    mapping : (n_source,) int
        Target vertex of each source vertex, numbering of these meshes (-1 = unmapped).
    k : int
        Laplace-Beltrami basis size, 2 .. n - 1 for the smaller mesh's n vertices (as
        :func:`meshcorr.spectral.fmap.functional_map`'s).
    n_nearest : int
        Target vertices, nearest in the spectral domain, whose triangles are searched.
    random_state : int or None
        Seed of the eigensolvers.

    Returns
    -------
    precise : PreciseMap
        Triangles in ``target.faces`` (indices into it), vertices in ``target.kept`` numbering.

    Raises
    ------
    MeshError
        The target is a point cloud (it has no triangles).
    ParameterError
        ``k`` or ``n_nearest`` out of range, or a map that does not fit the meshes.
    """
    n_nearest = check_int("n_nearest", n_nearest, minimum=1)
    if target.is_cloud:
        raise MeshError(f"{target.name} is a point cloud: a precise map sends each source vertex to a point "
                        "on a target triangle, and a cloud has none. Use the vertex map (result.map), or match "
                        "onto a triangle mesh of the target.")
    k = check_int("k", k, minimum=2)
    role, n = min(("source", source.n_vertices), ("target", target.n_vertices), key=lambda item: item[1])
    try:  # functional_map's bound (it was lowered here in silence), with the count it comes from
        check_int("k", k, maximum=n - 1)
    except ParameterError as error:
        raise ParameterError(f"{error} The {role} mesh has {n} vertices, and a Laplace-Beltrami basis of "
                             f"n vertices holds at most n - 1 = {n - 1} functions: give k <= {n - 1}.") from None
    fmap = functional_map(source, target, mapping, k, random_state=random_state)
    mapped = np.flatnonzero(np.asarray(mapping) >= 0)
    queries = (fmap.source_basis @ fmap.C)[mapped]
    phi = fmap.target_basis
    faces = np.asarray(target.faces)
    n_nearest = min(n_nearest, target.n_vertices)
    _, nearest = cKDTree(phi).query(queries, k=n_nearest, workers=-1)
    nearest = nearest.reshape(len(mapped), n_nearest)
    order, start = _vertex_faces(faces, target.n_vertices)
    counts = (start[1:] - start[:-1])[nearest]  # faces around each candidate vertex
    query_of = np.repeat(np.repeat(np.arange(len(mapped)), n_nearest), counts.reshape(-1))
    # the incident faces of every candidate vertex, gathered without a Python loop
    firsts = np.repeat(start[nearest.reshape(-1)], counts.reshape(-1))
    within = np.arange(len(firsts)) - np.repeat(np.cumsum(counts.reshape(-1)) - counts.reshape(-1), counts.reshape(-1))
    candidate = order[firsts + within]
    # a face around several candidate vertices is projected once
    key = np.unique(query_of * len(faces) + candidate)
    query_of, candidate = key // len(faces), key % len(faces)
    corners = faces[candidate]
    weights, distance2 = project_to_triangles(queries[query_of], phi[corners[:, 0]], phi[corners[:, 1]],
                                              phi[corners[:, 2]])
    pick = np.lexsort((distance2, query_of))
    first = pick[np.r_[True, query_of[pick][1:] != query_of[pick][:-1]]] if len(pick) else pick
    out_faces = np.full(source.n_original, -1, dtype=np.int64)
    out_weights = np.full((source.n_original, 3), np.nan)
    rows = source.kept[mapped]
    out_faces[rows], out_weights[rows] = candidate[first], weights[first]
    if len(first) != len(mapped):  # pragma: no cover - every target vertex has a face
        raise ParameterError("Some mapped source vertices found no target triangle.")
    return PreciseMap(faces=out_faces, weights=out_weights, target_faces=target.kept[faces])
