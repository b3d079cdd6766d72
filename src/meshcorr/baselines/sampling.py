"""Farthest-point sampling: an even, seeded subset of a point set.

Greedy farthest-point sampling (Gonzalez, "Clustering to minimize the
maximum intercluster distance", Theor. Comput. Sci. 1985; Eldar et al.,
"The farthest point strategy for progressive image sampling", IEEE TIP
1997): start from a seeded random point, then repeatedly add the point
farthest (Euclidean) from those chosen. ``O(n m)`` time, ``O(n)`` memory.
The greedy loop is that of the landmark vertices,
:func:`meshcorr.core.sampling.farthest_point_indices`, here on squared
Euclidean distances (the same order as the distances).
"""

from __future__ import annotations

import numpy as np

from ..core.sampling import farthest_point_indices


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
        Distinct row indices, in the order chosen (the first drawn with ``random_state``).
    """
    n = len(points)
    if n_samples >= n:
        return np.arange(n)
    return farthest_point_indices(lambda i: np.sum((points - points[i]) ** 2, axis=1), n, n_samples,
                                  random_state=random_state)[0]
