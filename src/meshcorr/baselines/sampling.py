"""Farthest-point sampling: an even, seeded subset of a point set.

Greedy farthest-point sampling (Gonzalez, "Clustering to minimize the
maximum intercluster distance", Theor. Comput. Sci. 1985; Eldar et al.,
"The farthest point strategy for progressive image sampling", IEEE TIP
1997): start from a seeded random point, then repeatedly add the point
farthest (Euclidean) from those chosen. ``O(n m)`` time, ``O(n)`` memory.
"""

from __future__ import annotations

import numpy as np


def farthest_point_sample(points: np.ndarray, n_samples: int, *, random_state: int | None = 0) -> np.ndarray:
    """Indices of an evenly spread subset of ``points``.

    Parameters
    ----------
    points : (n, d) float
    n_samples : int
        Subset size; all points (in order) if ``n_samples >= n``.
    random_state : int or None
        Seed of the first point.

    Returns
    -------
    indices : (min(n, n_samples),) int
        Distinct row indices, in the order chosen.
    """
    n = len(points)
    if n_samples >= n:
        return np.arange(n)
    rng = np.random.default_rng(random_state)
    chosen = np.empty(n_samples, dtype=np.int64)
    chosen[0] = rng.integers(n)
    nearest = np.sum((points - points[chosen[0]]) ** 2, axis=1)
    for m in range(1, n_samples):
        chosen[m] = int(np.argmax(nearest))
        np.minimum(nearest, np.sum((points - points[chosen[m]]) ** 2, axis=1), out=nearest)
    return chosen
