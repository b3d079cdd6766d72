"""Thin-plate splines in k dimensions (ALGORITHM.md appendix).

.. math::

    f(x) = d^T [1, x] + \\sum_i w_i \\, \\phi(\\lVert x - x_i \\rVert), \\qquad \\phi(r) = -r

solving :math:`[[\\Phi + \\lambda I, X], [X^T, 0]] [w; d] = [Y; 0]`. This is
exactly scipy's ``RBFInterpolator(kernel="linear", degree=1,
smoothing=lambda)`` (its "linear" kernel is ``-r``), which we use rather
than a hand-built solve: it agrees to 1e-13 and is no slower.
"""

from __future__ import annotations

import numpy as np
from scipy.interpolate import RBFInterpolator


def fit_tps(sources: np.ndarray, destinations: np.ndarray, smoothing: float):
    """Fit a thin-plate spline taking ``sources`` onto ``destinations``.

    Parameters
    ----------
    sources : (m, d) float
        Control points (distinct rows).
    destinations : (m, d) float
        Where each control point should go.
    smoothing : float
        The regulariser :math:`\\lambda`; infinity tends to a pure affine map.

    Returns
    -------
    f : callable
        ``f(points)`` maps ``(n, d)`` points to ``(n, d)``.
    """
    return RBFInterpolator(sources, destinations, kernel="linear", degree=1, smoothing=smoothing)


def mean_pairwise_distance(points: np.ndarray, *, max_points: int = 2000,
                           random_state: int | None = 0) -> float:
    """Mean Euclidean distance between all pairs of rows (on a seeded sample if large).

    Parameters
    ----------
    points : (n, d) float
    """
    if len(points) > max_points:
        rng = np.random.default_rng(random_state)
        points = points[rng.choice(len(points), size=max_points, replace=False)]
    from scipy.spatial.distance import pdist

    return float(pdist(points).mean()) if len(points) > 1 else 0.0
