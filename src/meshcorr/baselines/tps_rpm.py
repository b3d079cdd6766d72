"""TPS-RPM: non-rigid point matching by soft-assign and deterministic annealing, in 3D.

Chui & Rangarajan warp a moving point set :math:`V` (here: source samples,
``K`` points) onto a fixed one :math:`X` (target samples, ``N`` points) with
a thin-plate spline :math:`f`, alternating at each temperature :math:`T`:

1. **soft-assign** (with an outlier row and column, index ``K+1``, ``N+1``):

   .. math::

       m_{ai} = \\frac{1}{T} \\exp\\left(-\\frac{\\lVert x_i - f(v_a) \\rVert^2}{2T}\\right),
       \\quad m_{a,N+1} = \\frac{1}{T_0} \\exp\\left(-\\frac{\\lVert \\bar x - f(v_a) \\rVert^2}{2T_0}\\right),
       \\quad m_{K+1,i} = \\frac{1}{T_0} \\exp\\left(-\\frac{\\lVert x_i - \\bar v \\rVert^2}{2T_0}\\right)

   (:math:`\\bar x, \\bar v` the centroids, :math:`T_0` the initial
   temperature), then Sinkhorn's alternating row and column normalisation:
   rows :math:`a \\le K` and columns :math:`i \\le N` sum to one, the outlier
   row and column absorb the slack;
2. **spline update**: each :math:`v_a` gets the target
   :math:`y_a = \\sum_i m_{ai} x_i / \\sum_i m_{ai}` and :math:`f` minimises
   :math:`\\sum_a \\mu_a \\lVert y_a - f(v_a) \\rVert^2 + \\lambda_1\\,\\mathrm{tr}(w^T \\Phi w)
   + \\lambda_2 \\lVert A - I \\rVert_F^2`,
   :math:`\\mu_a = \\sum_{i \\le N} m_{ai}` (points matched to the outlier
   count less), :math:`A` the linear part of the affine term, with the 3D
   spline kernel :math:`\\phi(r) = -r` (:mod:`meshcorr.stages.tps`) and
   :math:`\\lambda_1 = \\lambda_{1,0} K T`, :math:`\\lambda_2 = \\lambda_{2,0} K T`:
   both regularisers are annealed with :math:`T` (see :class:`RegularisedTPS`).

:math:`T` starts at the largest squared distance between the point sets
(times ``t_init_factor``) and falls geometrically (``anneal_rate``) to the
mean squared nearest-neighbour distance within :math:`V`. Both point sets
are first scaled together so the target has unit RMS radius (so
the regularisers do not depend on the units).

For meshes, both vertex sets are subsampled to at most ``n_points`` by
farthest-point sampling, the final spline is evaluated at every source
vertex, and each warped source vertex takes its nearest target vertex.

Differences from the paper: the soft-assign is weighted into the spline fit
through :math:`\\mu_a`; the affine regulariser leaves the translation free;
the defaults :math:`\\lambda_{1,0} = \\lambda_{2,0} = 1` were chosen on one
TOSCA pair (cat0-cat1, hand-aligned: mean error 0.063; with
:math:`\\lambda_{2,0} = 0.01` the early, near-uniform matches collapse the
map and it came out at 0.28). ``benchmarks/baselines.py`` measures them.

Reference
---------
H. Chui, A. Rangarajan, "A new point matching algorithm for non-rigid
registration", Computer Vision and Image Understanding 89(2-3):114-141, 2003.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

import numpy as np
from scipy.spatial import cKDTree
from scipy.spatial.distance import cdist

from ..runtime.checks import check_float, check_int
from ..runtime.threads import single_blas_thread
from ..core.mesh import MeshLike
from ..maps.result import Correspondence
from ..runtime.timing import StageProgress, StageTimer
from ._common import finish, load_pair, nearest_map, spatial_points
from .sampling import farthest_point_sample


@dataclass
class TPSRPMResult:
    """Outcome of :func:`tps_rpm`.

    Attributes
    ----------
    warp : callable
        ``warp(points)`` maps ``(n, 3)`` points of the source's space to the
        target's (the last spline, in the input units).
    assignment : (K, N) float
        The last soft-assign matrix without its outlier row and column.
    history : list of dict
        Per temperature: ``temperature``, ``smoothing``, ``energy`` (the
        assignment-weighted mean squared distance).
    """

    warp: Callable[[np.ndarray], np.ndarray]
    assignment: np.ndarray
    history: list = field(default_factory=list)


class _Spline:
    """:math:`f(x) = [1, x]\\, d + \\sum_a w_a \\phi(\\lVert x - v_a \\rVert)`, :math:`\\phi(r) = -r`."""

    def __init__(self, centres: np.ndarray, w: np.ndarray, d: np.ndarray) -> None:
        self.centres, self.w, self.d = centres, w, d

    def __call__(self, points: np.ndarray) -> np.ndarray:
        return _homogeneous(points) @ self.d - cdist(points, self.centres) @ self.w


def _homogeneous(points: np.ndarray) -> np.ndarray:
    return np.hstack([np.ones((len(points), 1)), points])


class RegularisedTPS:
    """Weighted thin-plate splines with a regularised affine part on fixed control points.

    :meth:`fit` minimises (Chui & Rangarajan, sec. 4.2)

    .. math::

        \\sum_a \\mu_a \\lVert y_a - f(v_a) \\rVert^2 + \\lambda_1 \\mathrm{tr}(w^T \\Phi w)
        + \\lambda_2 \\lVert A - I \\rVert_F^2

    over splines with :math:`[1, V]^T w = 0`, :math:`A` the linear part of
    :math:`d` (the translation is free). Writing :math:`w = N\\gamma` with
    :math:`N` an orthonormal basis of the null space of :math:`[1, V]^T`
    (QR, computed once), the minimiser solves one ``K x K`` symmetric
    system. :math:`\\lambda_2` stops the soft-assign's early, uniform matches
    from collapsing the map to a point (which loses the orientation).

    Parameters
    ----------
    V : (K, 3) float
        Control points.
    """

    def __init__(self, V: np.ndarray) -> None:
        self.V = V
        K, self.dim = V.shape
        Vh = _homogeneous(V)
        self.N = np.linalg.qr(Vh, mode="complete")[0][:, self.dim + 1:]
        Phi = -cdist(V, V)
        self.A = np.hstack([Phi @ self.N, Vh])
        self.bending = self.N.T @ Phi @ self.N

    def fit(self, Y: np.ndarray, weights: np.ndarray, smoothing: float, affine_smoothing: float) -> _Spline:
        """The spline taking the control points towards ``Y``.

        Parameters
        ----------
        Y : (K, 3) float
            Destinations of the control points.
        weights : (K,) float
            :math:`\\mu_a \\ge 0`.
        smoothing : float
            :math:`\\lambda_1 > 0`.
        affine_smoothing : float
            :math:`\\lambda_2 \\ge 0`.
        """
        K, dim, m = len(self.V), self.dim, self.bending.shape[0]
        lhs = self.A.T @ (weights[:, None] * self.A)
        lhs[:m, :m] += smoothing * self.bending
        lhs[m + 1:, m + 1:] += affine_smoothing * np.eye(dim)
        rhs = self.A.T @ (weights[:, None] * Y)
        rhs[m + 1:] += affine_smoothing * np.eye(dim)
        z = np.linalg.solve(lhs, rhs)
        return _Spline(self.V, self.N @ z[:m], z[m:])


def _softassign(D2: np.ndarray, out_col: np.ndarray, out_row: np.ndarray, T: float, T0: float,
                iterations: int) -> np.ndarray:
    """Sinkhorn-normalised ``(K + 1, N + 1)`` match matrix (see the module docstring).

    ``D2`` holds the squared distances :math:`\\lVert x_i - f(v_a) \\rVert^2`,
    ``out_col`` / ``out_row`` those to the outlier cluster centres. Built in
    the log domain and shifted by its maximum, so nothing overflows; entries
    that underflow to 0 are negligible, and every row and column keeps its
    outlier entry, which does not.
    """
    K, N = D2.shape
    logM = np.full((K + 1, N + 1), -np.inf)
    logM[:K, :N] = -D2 / (2.0 * T) - np.log(T)
    logM[:K, N] = -out_col / (2.0 * T0) - np.log(T0)
    logM[K, :N] = -out_row / (2.0 * T0) - np.log(T0)
    E = np.exp(logM - logM.max())
    # Sinkhorn as diagonal scalings M = diag(r) E diag(c): rows a < K and
    # columns i < N are normalised in turn; the outlier row and column keep scale 1.
    r, c = np.ones(K + 1), np.ones(N + 1)
    for _ in range(iterations):
        r[:K] = 1.0 / (E[:K] @ c)
        c[:N] = 1.0 / (r @ E[:, :N])
    return r[:, None] * E * c[None, :]


def tps_rpm(V: np.ndarray, X: np.ndarray, *, lambda_init: float = 1.0, affine_init: float = 1.0,
            anneal_rate: float = 0.93,
            t_init_factor: float = 1.0, t_final: float | None = None, inner_iterations: int = 5,
            sinkhorn_iterations: int = 30) -> TPSRPMResult:
    """Warp point set ``V`` onto point set ``X`` with TPS-RPM.

    Parameters
    ----------
    V : (K, 3) float
        Moving points (the source sample).
    X : (N, 3) float
        Fixed points (the target sample).
    lambda_init : float
        :math:`\\lambda_{1,0}` (> 0): the bending regulariser is
        :math:`\\lambda_{1,0} K T`.
    affine_init : float
        :math:`\\lambda_{2,0} \\ge 0`: the affine regulariser is
        :math:`\\lambda_{2,0} K T` (see :class:`RegularisedTPS`).
    anneal_rate : float in (0, 1)
        Temperature factor per step (paper: 0.93).
    t_init_factor : float
        Initial temperature as a multiple of the largest squared distance
        between the sets (> 0).
    t_final : float, optional
        Final temperature; default the mean squared nearest-neighbour
        distance within ``V`` (after normalisation to unit RMS radius).
    inner_iterations : int
        Soft-assign / spline alternations per temperature (paper: 5).
    sinkhorn_iterations : int
        Row-column normalisations per soft-assign.

    Returns
    -------
    result : TPSRPMResult
    """
    lambda_init = check_float("lambda_init", lambda_init, minimum=0.0, exclusive=True)
    affine_init = check_float("affine_init", affine_init, minimum=0.0)
    anneal_rate = check_float("anneal_rate", anneal_rate, minimum=0.0, exclusive=True, maximum=0.999)
    t_init_factor = check_float("t_init_factor", t_init_factor, minimum=0.0, exclusive=True)
    if t_final is not None:
        t_final = check_float("t_final", t_final, minimum=0.0, exclusive=True)
    inner_iterations = check_int("inner_iterations", inner_iterations, minimum=1)
    sinkhorn_iterations = check_int("sinkhorn_iterations", sinkhorn_iterations, minimum=1)

    # One similarity for both sets: the target centred at 0 with unit RMS radius.
    centre = X.mean(axis=0)
    unit = 1.0 / np.sqrt(np.mean(np.sum((X - centre) ** 2, axis=1)))
    V, X = (V - centre) * unit, (X - centre) * unit
    K = len(V)

    T0 = t_init_factor * float(cdist(V, X, "sqeuclidean").max())
    if t_final is None:
        t_final = float(np.mean(cKDTree(V).query(V, k=2)[0][:, 1] ** 2))
    T = T0
    moved = V.copy()
    spline = None
    system = RegularisedTPS(V)
    history = []
    out_row = np.sum((X - V.mean(axis=0)) ** 2, axis=1)
    x_bar = X.mean(axis=0)
    # Many small dense solves: BLAS threads only add overhead (10x slower on a busy 2-core machine).
    with single_blas_thread():
        while True:
            smoothing, affine_smoothing = lambda_init * K * T, affine_init * K * T
            for _ in range(inner_iterations):
                D2 = cdist(moved, X, "sqeuclidean")
                M = _softassign(D2, np.sum((moved - x_bar) ** 2, axis=1), out_row, T, T0, sinkhorn_iterations)
                mass = M[:K, :X.shape[0]].sum(axis=1)
                Y = M[:K, :X.shape[0]] @ X / np.maximum(mass, 1e-12)[:, None]
                spline = system.fit(Y, mass, smoothing, affine_smoothing)
                moved = spline(V)
            P = M[:K, :X.shape[0]]
            history.append({"temperature": T, "smoothing": smoothing, "affine_smoothing": affine_smoothing,
                            "energy": float((P * D2).sum() / max(P.sum(), 1e-12))})
            if T <= t_final:
                break
            T = max(T * anneal_rate, t_final)

    final = spline

    def warp(points: np.ndarray) -> np.ndarray:
        return final((np.asarray(points, dtype=float) - centre) * unit) / unit + centre

    return TPSRPMResult(warp, P, history)


def match_tps_rpm(source: MeshLike, target: MeshLike, *, prealign: bool = True, n_points: int = 500,
                  lambda_init: float = 1.0, affine_init: float = 1.0, anneal_rate: float = 0.93,
                  inner_iterations: int = 5,
                  bijective: bool = False, largest_component: bool = False, random_state: int | None = 0,
                  progress: StageProgress | None = None) -> Correspondence:
    """Vertex map by TPS-RPM: warp the source onto the target, take nearest target vertices.

    Parameters
    ----------
    source, target : path, trimesh.Trimesh, Mesh or (vertices, faces)
    prealign : bool
        Centre, scale and rotate each mesh to its principal axes first
        (:mod:`meshcorr.baselines.align`). TPS-RPM is not rotation
        invariant: without it the inputs must already be roughly aligned.
    n_points : int
        At most this many farthest-point samples of each mesh take part in
        the matching (>= 10).
    lambda_init, affine_init, anneal_rate, inner_iterations
        See :func:`tps_rpm`.
    bijective : bool
        One-to-one final map by linear assignment (equal vertex counts only).
    largest_component : bool
        Map only the largest connected component of each mesh.
    random_state : int or None
        Seed of the farthest-point samples.
    progress : callable, optional
        ``progress(stage, done, total)``.

    Returns
    -------
    result : Correspondence
        ``method="tps-rpm"``; ``cost`` is each warped vertex's distance to
        its match (in pre-aligned units when ``prealign``).
    """
    n_points = check_int("n_points", n_points, minimum=10)
    timer = StageTimer(progress)
    src, tgt = load_pair(source, target, largest_component=largest_component, timer=timer)
    P, Q = spatial_points(src, tgt, prealign=prealign, timer=timer)
    with timer.stage("sample"):
        sp = farthest_point_sample(P, n_points, random_state=random_state)
        sq = farthest_point_sample(Q, n_points, random_state=random_state)
    with timer.stage("tps-rpm"):
        rpm = tps_rpm(P[sp], Q[sq], lambda_init=lambda_init, affine_init=affine_init, anneal_rate=anneal_rate,
                      inner_iterations=inner_iterations)
        warped = rpm.warp(P)
    with timer.stage("matching"):
        local_map, local_cost = nearest_map(warped, Q, bijective=bijective)
    params = dict(prealign=prealign, n_points=n_points, lambda_init=lambda_init, affine_init=affine_init,
                  anneal_rate=anneal_rate,
                  inner_iterations=inner_iterations, bijective=bijective,
                  largest_component=largest_component, random_state=random_state)
    return finish("tps-rpm", src, tgt, local_map, local_cost, timer, params)
