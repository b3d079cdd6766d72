"""Robust rigid ICP with uniform scale, in 3D space.

Iterative closest point (Besl & McKay 1992) moving the source onto the
target with a similarity :math:`p \\mapsto s R p + t`. Each iteration

1. matches every moved source point to its nearest target point,
   :math:`j(i) = \\arg\\min_j \\lVert s R p_i + t - q_j \\rVert`, distance :math:`r_i`;
2. keeps the ``trim`` fraction of pairs with the smallest :math:`r_i`
   (trimmed ICP, Chetverikov et al. 2002) and optionally down-weights the
   rest with Huber weights :math:`w_i = \\min(1, \\delta / r_i)`,
   :math:`\\delta` = ``huber`` times the median kept distance;
3. refits the similarity in closed form (Umeyama 1991):

   .. math::

       \\min_{s, R, t} \\sum_i w_i \\lVert q_{j(i)} - (s R p_i + t) \\rVert^2

until no match changes or the trimmed mean distance stops decreasing.
Several initial rotations (the identity, the three half-turns about the
coordinate axes, i.e. the sign ambiguities of a PCA pre-alignment, then
seeded random rotations) can be tried; the lowest final cost wins.

References
----------
P. J. Besl, N. D. McKay, "A method for registration of 3-D shapes", IEEE
PAMI 14(2):239-256, 1992.
D. Chetverikov, D. Svirko, D. Stepanov, P. Krsek, "The trimmed iterative
closest point algorithm", ICPR 2002.
S. Umeyama, "Least-squares estimation of transformation parameters between
two point patterns", IEEE PAMI 13(4):376-380, 1991.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.spatial import cKDTree
from scipy.spatial.transform import Rotation

from ..runtime.checks import check_float, check_int
from ..runtime.threads import kdtree_query
from ..core.mesh import MeshLike
from ..maps.result import Correspondence
from ..runtime.timing import StageProgress, StageTimer
from ._common import finish, load_pair, nearest_map, spatial_points
from .align import HALF_TURNS, Similarity


def umeyama(P: np.ndarray, Q: np.ndarray, weights: np.ndarray | None = None, *,
            with_scale: bool = True) -> Similarity:
    """Weighted least-squares similarity taking ``P`` onto ``Q`` (Umeyama 1991).

    Parameters
    ----------
    P, Q : (n, 3) float
        Paired points.
    weights : (n,) float, optional
        Non-negative pair weights; uniform if omitted.
    with_scale : bool
        Fit the uniform scale; ``False`` fixes it to 1 (rigid motion).

    Returns
    -------
    transform : Similarity
        Minimises :math:`\\sum_i w_i \\lVert Q_i - (s R P_i + t) \\rVert^2`
        over proper rotations R.
    """
    w = np.ones(len(P)) if weights is None else np.asarray(weights, dtype=float)
    w = w / w.sum()
    mu_p, mu_q = w @ P, w @ Q
    Pc, Qc = P - mu_p, Q - mu_q
    U, D, Vt = np.linalg.svd((Qc * w[:, None]).T @ Pc)
    S = np.ones(3)
    if np.linalg.det(U) * np.linalg.det(Vt) < 0:
        S[2] = -1.0
    R = (U * S) @ Vt
    s = float((D * S).sum() / (w @ np.sum(Pc**2, axis=1))) if with_scale else 1.0
    return Similarity(s, R, mu_q - s * R @ mu_p)


@dataclass
class RigidICPResult:
    """Outcome of :func:`rigid_icp`.

    Attributes
    ----------
    transform : Similarity
        Source -> target similarity.
    matches : (n1,) int
        Nearest target point of each moved source point.
    distances : (n1,) float
        Their distances.
    cost : float
        Trimmed mean of ``distances`` (the criterion that picks the start).
    history : list of dict
        Per iteration of the winning start: ``iteration``, ``cost``,
        ``changed`` (fraction of matches changed since the previous
        iteration), ``scale``, measured before that iteration's fit.
    converged : bool
    start : int
        Index of the winning initial rotation.
    """

    transform: Similarity
    matches: np.ndarray
    distances: np.ndarray
    cost: float
    history: list = field(default_factory=list)
    converged: bool = False
    start: int = 0


def initial_rotations(n_rotations: int, random_state: int | None = 0) -> list[np.ndarray]:
    """The identity, the three half-turns about the axes, then seeded random rotations, ``n_rotations`` in all."""
    rotations = list(HALF_TURNS[:n_rotations])
    if n_rotations > len(HALF_TURNS):
        extra = Rotation.random(n_rotations - len(HALF_TURNS), random_state=random_state).as_matrix()
        rotations += list(extra.reshape(-1, 3, 3))
    return rotations


def _kept(distances: np.ndarray, trim: float) -> np.ndarray:
    n_keep = max(3, int(np.ceil(trim * len(distances))))
    return np.argsort(distances, kind="stable")[:n_keep]


def _icp_from(P, Q, tree, start: Similarity, *, max_iter, trim, huber, with_scale, tol) -> RigidICPResult:
    transform, previous, history, converged = start, None, [], False
    for iteration in range(max_iter + 1):
        dist, matches = kdtree_query(tree, transform.apply(P))
        keep = _kept(dist, trim)
        cost = float(dist[keep].mean())
        changed = 1.0 if previous is None else float(np.mean(matches != previous))
        history.append({"iteration": iteration, "cost": cost, "changed": changed, "scale": transform.scale})
        if previous is not None and (changed == 0.0 or history[-2]["cost"] - cost <= tol * history[-2]["cost"]):
            converged = True
            break
        if iteration == max_iter:
            break
        weights = None
        if huber is not None:
            delta = huber * np.median(dist[keep])
            weights = np.minimum(1.0, delta / np.maximum(dist[keep], 1e-300))
        transform = umeyama(P[keep], Q[matches[keep]], weights, with_scale=with_scale)
        previous = matches
    return RigidICPResult(transform, matches, dist, cost, history, converged)


def rigid_icp(P: np.ndarray, Q: np.ndarray, *, trim: float = 0.9, huber: float | None = None,
              with_scale: bool = True, n_rotations: int = 1, max_iter: int = 50, tol: float = 1e-6,
              random_state: int | None = 0) -> RigidICPResult:
    """Robust similarity ICP taking source points ``P`` onto target points ``Q``.

    Parameters
    ----------
    P : (n1, 3) float
        Source points (moved).
    Q : (n2, 3) float
        Target points (fixed).
    trim : float in (0, 1]
        Fraction of pairs, the closest, used in each fit (1 = plain ICP).
    huber : float or None
        Huber threshold as a multiple of the median kept distance (> 0);
        None for unweighted pairs.
    with_scale : bool
        Fit a uniform scale as well as the rigid motion.
    n_rotations : int
        Initial rotations tried (about the source centroid, centroids
        superposed): 1 = the identity only, 4 = also the three half-turns
        about the axes, more = also seeded random rotations.
    max_iter : int
        Most iterations per start.
    tol : float
        Stop when the trimmed mean distance falls by less than this
        relative amount.
    random_state : int or None
        Seed of the random initial rotations.

    Returns
    -------
    result : RigidICPResult
    """
    trim = check_float("trim", trim, minimum=0.0, exclusive=True, maximum=1.0)
    if huber is not None:
        huber = check_float("huber", huber, minimum=0.0, exclusive=True)
    n_rotations = check_int("n_rotations", n_rotations, minimum=1)
    max_iter = check_int("max_iter", max_iter, minimum=0)
    tree = cKDTree(Q)
    mu_p, mu_q = P.mean(axis=0), Q.mean(axis=0)
    best = None
    for number, R0 in enumerate(initial_rotations(n_rotations, random_state)):
        start = Similarity(1.0, R0, mu_q - R0 @ mu_p)
        result = _icp_from(P, Q, tree, start, max_iter=max_iter, trim=trim, huber=huber,
                           with_scale=with_scale, tol=tol)
        result.start = number
        if best is None or result.cost < best.cost:
            best = result
    return best


def match_icp(source: MeshLike, target: MeshLike, *, prealign: bool = True, trim: float = 0.9,
              huber: float | None = None, with_scale: bool = True, n_rotations: int = 1, max_iter: int = 50,
              bijective: bool = False, largest_component: bool = False, random_state: int | None = 0,
              progress: StageProgress | None = None) -> Correspondence:
    """Vertex map by robust rigid ICP: each moved source vertex takes its nearest target vertex.

    Parameters
    ----------
    source, target : path, trimesh.Trimesh, Mesh or (vertices, faces)
    prealign : bool
        Centre, scale and rotate each mesh to its principal axes first
        (:mod:`meshcorr.baselines.align`); without it ICP starts from the
        input poses with the centroids superposed.
    trim, huber, with_scale, n_rotations, max_iter
        See :func:`rigid_icp`.
    bijective : bool
        One-to-one final map by linear assignment (equal vertex counts only).
    largest_component : bool
        Map only the largest connected component of each mesh.
    random_state : int or None
        Seed of the random initial rotations.
    progress : callable, optional
        ``progress(stage, done, total)``.

    Returns
    -------
    result : Correspondence
        ``method="icp"``; ``cost`` is each moved vertex's distance to its
        match (in pre-aligned units when ``prealign``); ``icp_history`` holds
        the winning start's iterations.
    """
    timer = StageTimer(progress)
    src, tgt = load_pair(source, target, largest_component=largest_component, timer=timer)
    P, Q = spatial_points(src, tgt, prealign=prealign, timer=timer)
    with timer.stage("icp"):
        icp = rigid_icp(P, Q, trim=trim, huber=huber, with_scale=with_scale, n_rotations=n_rotations,
                        max_iter=max_iter, random_state=random_state)
    with timer.stage("matching"):
        local_map, local_cost = nearest_map(icp.transform.apply(P), Q, bijective=bijective)
    params = dict(prealign=prealign, trim=trim, huber=huber, with_scale=with_scale, n_rotations=n_rotations,
                  max_iter=max_iter, bijective=bijective, largest_component=largest_component,
                  random_state=random_state)
    return finish("icp", src, tgt, local_map, local_cost, timer, params,
                  icp_history=icp.history, icp_converged=icp.converged)
