"""Farthest-point sampling of landmark vertices.

Greedy farthest-point sampling (Gonzalez 1985; Eldar et al., "The farthest
point strategy for progressive image sampling", IEEE TIP 1997): start from
one vertex, then repeatedly add the vertex farthest from every landmark
chosen so far,

.. math::

    l_{t+1} = \\arg\\max_v \\min_{s \\le t} d(v, l_s), \\qquad
    r_t = \\max_v \\min_{s \\le t} d(v, l_s),

where :math:`r_t` is the covering radius after ``t`` landmarks (every
vertex lies within :math:`r_t` of a landmark). It is non-increasing, and the
sampling is a 2-approximation of the optimal covering (k-centre) problem.
The distance rows from every landmark are computed anyway, so they are
returned: they are exactly what the landmark (Nyström) spectrum needs, and
their maximum is a lower bound of the mesh's diameter that the second
landmark (the vertex farthest from the first) already makes tight to within
the solver's accuracy on typical shapes.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from ..runtime.checks import check_int

RowFn = Callable[[int], np.ndarray]


@dataclass
class Landmarks:
    """The outcome of :func:`farthest_point_sampling`.

    Attributes
    ----------
    indices : (m,) int
        Landmark vertices, in the order they were chosen.
    distances : (m, n) float
        ``distances[t]`` holds the distances from landmark t to every vertex.
    radii : (m,) float
        ``radii[t]`` is the covering radius once landmarks ``0..t`` are
        chosen (non-increasing).
    """

    indices: np.ndarray
    distances: np.ndarray
    radii: np.ndarray

    @property
    def diameter(self) -> float:
        """Largest distance seen from any landmark: a lower bound of the mesh's diameter."""
        return float(self.distances.max())


def farthest_point_sampling(distances_from: RowFn, n_vertices: int, n_landmarks: int, *,
                            start: int | None = None, random_state: int | None = 0) -> Landmarks:
    """Well-spread landmark vertices by greedy farthest-point sampling.

    Parameters
    ----------
    distances_from : callable
        ``distances_from(i)`` returns the distances from vertex i to every
        vertex, ``(n,)`` (geodesic from a single-source solve, or along mesh
        edges for a cheaper graph metric).
    n_vertices : int
        n.
    n_landmarks : int
        m, landmarks to choose (at most n).
    start : int, optional
        The first landmark; drawn with ``random_state`` when omitted.
    random_state : int or None
        Seed of the first landmark.

    Returns
    -------
    landmarks : Landmarks
        ``m`` distinct vertices with their distance rows and covering radii.
        Costs ``m`` calls of ``distances_from`` and ``O(m n)`` time.
    """
    n_vertices = check_int("n_vertices", n_vertices, minimum=1)
    m = check_int("n_landmarks", n_landmarks, minimum=1, maximum=n_vertices)
    rows = np.empty((m, n_vertices))
    indices, radii = _greedy(distances_from, n_vertices, m, _first(start, n_vertices, random_state), rows)
    return Landmarks(indices, rows, radii)


def farthest_point_indices(distances_from: RowFn, n_vertices: int, n_landmarks: int, *,
                           start: int | None = None, random_state: int | None = 0
                           ) -> tuple[np.ndarray, np.ndarray]:
    """``(m,)`` int landmarks and ``(m,)`` covering radii of :func:`farthest_point_sampling`, rows not kept.

    The same greedy sampling in ``O(n)`` memory (the distance rows are
    dropped once used): for samples of many points. Parameters as
    :func:`farthest_point_sampling`; ``distances_from`` may give any
    distance that orders points as the metric does (e.g. squared
    Euclidean), and the radii are then in its units.
    """
    n_vertices = check_int("n_vertices", n_vertices, minimum=1)
    m = check_int("n_landmarks", n_landmarks, minimum=1, maximum=n_vertices)
    return _greedy(distances_from, n_vertices, m, _first(start, n_vertices, random_state), None)


def _first(start: int | None, n_vertices: int, random_state: int | None) -> int:
    """The first landmark: ``start``, checked, or drawn with ``random_state``."""
    if start is None:
        start = int(np.random.default_rng(random_state).integers(n_vertices))
    return check_int("start", start, minimum=0, maximum=n_vertices - 1)


def _greedy(distances_from: RowFn, n_vertices: int, m: int, start: int,
            rows: np.ndarray | None) -> tuple[np.ndarray, np.ndarray]:
    """The greedy loop (module docstring): ``(m,)`` landmarks and radii; each row into ``rows`` if given."""
    indices = np.empty(m, dtype=np.int64)
    radii = np.empty(m)
    nearest = np.full(n_vertices, np.inf)
    current = start
    for t in range(m):
        indices[t] = current
        row = np.maximum(np.asarray(distances_from(current), dtype=np.float64), 0.0)
        row[current] = 0.0
        if rows is not None:
            rows[t] = row
        np.minimum(nearest, row, out=nearest)
        # Chosen vertices must not come back, even if a solver gives them a
        # tiny positive distance to themselves.
        nearest[indices[:t + 1]] = -np.inf
        current = int(np.argmax(nearest))
        radii[t] = max(float(nearest[current]), 0.0)
    return indices, radii
