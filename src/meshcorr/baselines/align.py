"""Pre-alignment of point sets for the spatial baselines.

Jain & Zhang hand-aligned the inputs of the three spatial baselines
(TPS-RPM, rigid ICP, 3D shape contexts). This module does it automatically
with the classical moment normalisation (e.g. Horn, "Robot Vision", 1986,
ch. 12; Vranic & Saupe, "3D model retrieval", 2001):

1. centre at the (area-weighted) centroid :math:`c = \\sum_i w_i p_i`;
2. scale to unit RMS radius, :math:`s = (\\sum_i w_i \\lVert p_i - c \\rVert^2)^{-1/2}`;
3. rotate onto the principal axes :math:`e_1, e_2, e_3` of the weighted
   covariance :math:`\\Sigma = \\sum_i w_i (p_i - c)(p_i - c)^T`, variance
   descending.

Sign convention: :math:`e_1` and :math:`e_2` point towards the positive third
moment (skewness) of the points' coordinates along them,
:math:`\\sum_i w_i ((p_i - c) \\cdot e_a)^3 > 0`, and :math:`e_3 = e_1 \\times e_2`,
so the rotation is proper (a shape is never mirrored). The result is
invariant to rigid motion, uniform scale and vertex order; it is ambiguous
only for shapes whose first two skewnesses vanish (symmetric shapes) or
whose principal variances coincide.

For a *pair* of shapes, :func:`align_pair` removes the sign ambiguity that
remains (a nearly symmetric or bent shape can have the "wrong" skewness
sign): of the four proper sign choices of the target's axes (the identity
and the half-turns about each axis), it keeps the one with the smallest
symmetric Chamfer distance to the aligned source, the way a person would
hand-align them.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

from ..runtime.threads import kdtree_query

#: The proper sign changes of three axes: the identity and the half-turns about each axis.
HALF_TURNS = (np.eye(3), np.diag([1.0, -1.0, -1.0]), np.diag([-1.0, 1.0, -1.0]), np.diag([-1.0, -1.0, 1.0]))


@dataclass(frozen=True)
class Similarity:
    """The map :math:`p \\mapsto s R p + t`.

    Attributes
    ----------
    scale : float
        s > 0.
    rotation : (3, 3) float
        R, a proper rotation.
    translation : (3,) float
        t.
    """

    scale: float
    rotation: np.ndarray
    translation: np.ndarray

    def apply(self, points: np.ndarray) -> np.ndarray:
        """Transformed points ``s * points @ R.T + t``, ``(n, 3)``."""
        return self.scale * np.asarray(points, dtype=float) @ self.rotation.T + self.translation

    def inverse(self) -> "Similarity":
        """The inverse map :math:`q \\mapsto s^{-1} R^T (q - t)`."""
        return Similarity(1.0 / self.scale, self.rotation.T, -(self.rotation.T @ self.translation) / self.scale)

    def then(self, other: "Similarity") -> "Similarity":
        """The composition ``other ∘ self`` (apply ``self`` first)."""
        return Similarity(other.scale * self.scale, other.rotation @ self.rotation,
                          other.scale * other.rotation @ self.translation + other.translation)


def barycentric_areas(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Barycentric vertex areas: a third of the area of each incident triangle.

    Parameters
    ----------
    vertices : (n, 3) float
    faces : (m, 3) int

    Returns
    -------
    areas : (n,) float
    """
    v = vertices[faces]
    face_area = 0.5 * np.linalg.norm(np.cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0]), axis=1)
    areas = np.zeros(len(vertices))
    np.add.at(areas, faces.ravel(), np.repeat(face_area / 3.0, 3))
    return areas


def pca_alignment(points: np.ndarray, weights: np.ndarray | None = None) -> Similarity:
    """The similarity taking ``points`` to their normalised pose (see the module docstring).

    Parameters
    ----------
    points : (n, 3) float
    weights : (n,) float, optional
        Non-negative point weights (e.g. :func:`barycentric_areas`, which makes
        the result insensitive to the tessellation); uniform if omitted.

    Returns
    -------
    alignment : Similarity
    """
    points = np.asarray(points, dtype=float)
    w = np.ones(len(points)) if weights is None else np.asarray(weights, dtype=float)
    w = w / w.sum()
    centre = w @ points
    centred = points - centre
    _, axes = np.linalg.eigh((centred * w[:, None]).T @ centred)
    axes = axes[:, ::-1]  # columns e1, e2, e3 by descending variance
    for a in range(2):
        if w @ (centred @ axes[:, a]) ** 3 < 0:
            axes[:, a] = -axes[:, a]
    axes[:, 2] = np.cross(axes[:, 0], axes[:, 1])
    scale = 1.0 / np.sqrt(w @ np.sum(centred**2, axis=1))
    rotation = axes.T
    return Similarity(scale, rotation, -scale * rotation @ centre)


def prealign(points: np.ndarray, weights: np.ndarray | None = None) -> np.ndarray:
    """Points centred, scaled to unit RMS radius and rotated to their principal axes.

    Parameters
    ----------
    points : (n, 3) float
    weights : (n,) float, optional
        See :func:`pca_alignment`.

    Returns
    -------
    aligned : (n, 3) float
    """
    return pca_alignment(points, weights).apply(points)


def chamfer_distance(P: np.ndarray, Q: np.ndarray) -> float:
    """Symmetric Chamfer distance: mean nearest-neighbour distance from P to Q plus from Q to P.

    Parameters
    ----------
    P : (n1, d) float
    Q : (n2, d) float
    """
    return float(kdtree_query(cKDTree(Q), P)[0].mean() + kdtree_query(cKDTree(P), Q)[0].mean())


def align_pair(P: np.ndarray, Q: np.ndarray, P_weights: np.ndarray | None = None,
               Q_weights: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Pre-align two point sets: each by :func:`prealign`, then the target's axis signs by Chamfer distance.

    Parameters
    ----------
    P : (n1, 3) float
        Source points.
    Q : (n2, 3) float
        Target points.
    P_weights, Q_weights : (n1,), (n2,) float, optional
        Point weights (see :func:`pca_alignment`).

    Returns
    -------
    P_aligned : (n1, 3) float
    Q_aligned : (n2, 3) float
        Invariant to rigid motion, uniform scale and vertex order of either input.
    """
    P_aligned, Q_aligned = prealign(P, P_weights), prealign(Q, Q_weights)
    candidates = [Q_aligned @ H for H in HALF_TURNS]  # H is diagonal: H.T == H
    best = min(range(len(candidates)), key=lambda c: chamfer_distance(P_aligned, candidates[c]))
    return P_aligned, candidates[best]
