"""Thin-plate splines in k dimensions (docs/method.md, step 5).

.. math::

    f(x) = d^T [1, x] + \\sum_i w_i \\, \\phi(\\lVert x - x_i \\rVert), \\qquad \\phi(r) = -r

solving :math:`[[\\Phi + \\lambda I, P], [P^T, 0]] [w; d] = [Y; 0]` with
:math:`P = [1, x]`. This is scipy's ``RBFInterpolator(kernel="linear",
degree=1, smoothing=lambda)`` (its "linear" kernel is ``-r``); it is written
out here because evaluating it is the inner loop of TPS-ICP, and
``cdist`` plus one matrix product evaluates it 2-3x faster than
``RBFInterpolator.__call__`` (1000-5000 points, 500 centres in 5-d: 2.3 vs
6.9 ms and 15 vs 46 ms on one core) with the same values to ~1e-13
(tests/stages/test_icp.py compares the two).
"""

from __future__ import annotations

import numpy as np
from scipy.spatial.distance import cdist

#: Rows evaluated per block (a ``block x m`` distance matrix at a time).
_EVAL_BLOCK = 8192


class ThinPlateSpline:
    """A fitted thin-plate spline: ``spline(points)`` maps ``(n, d)`` points to ``(n, d)``.

    Attributes
    ----------
    centres : (m, d) float
        The control points.
    weights : (m, d) float
        :math:`w`, the kernel coefficients.
    affine : (d + 1, d) float
        :math:`d`, the coefficients of ``[1, (x - shift) / scale]``.
    shift, scale : (d,) float and float
        Centring and scaling of the affine part's variables (conditioning only).
    """

    def __init__(self, centres, weights, affine, shift, scale) -> None:
        self.centres, self.weights, self.affine = centres, weights, affine
        self.shift, self.scale = shift, scale

    def __call__(self, points: np.ndarray) -> np.ndarray:
        points = np.asarray(points, dtype=np.float64)
        out = np.empty((len(points), self.weights.shape[1]))
        for start in range(0, len(points), _EVAL_BLOCK):
            block = points[start:start + _EVAL_BLOCK]
            values = ((block - self.shift) / self.scale) @ self.affine[1:]
            values += self.affine[0]
            values -= cdist(block, self.centres) @ self.weights  # phi(r) = -r
            out[start:start + _EVAL_BLOCK] = values
        return out


def fit_tps(sources: np.ndarray, destinations: np.ndarray, smoothing: float) -> ThinPlateSpline:
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
    f : ThinPlateSpline
        ``f(points)`` maps ``(n, d)`` points to ``(n, d)``.

    Raises
    ------
    numpy.linalg.LinAlgError
        If the system is singular (e.g. fewer than ``d + 1`` affinely
        independent control points and no smoothing).
    """
    sources = np.asarray(sources, dtype=np.float64)
    destinations = np.asarray(destinations, dtype=np.float64)
    m, d = sources.shape
    # As RBFInterpolator: the affine part's variables centred and scaled to [-1, 1].
    lo, hi = sources.min(axis=0), sources.max(axis=0)
    shift = (hi + lo) / 2
    scale = np.where(hi - lo > 0, (hi - lo) / 2, 1.0)
    system = np.zeros((m + d + 1, m + d + 1))
    system[:m, :m] = -cdist(sources, sources)
    system[np.arange(m), np.arange(m)] += smoothing
    system[:m, m] = system[m, :m] = 1.0
    system[:m, m + 1:] = (sources - shift) / scale
    system[m + 1:, :m] = system[:m, m + 1:].T
    rhs = np.zeros((m + d + 1, destinations.shape[1]))
    rhs[:m] = destinations
    coefficients = np.linalg.solve(system, rhs)  # LU (LAPACK gesv), as RBFInterpolator
    return ThinPlateSpline(sources, coefficients[:m], coefficients[m:], shift, scale)


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
