"""3D shape contexts matched by chi-square cost and linear assignment.

The descriptor of a point :math:`p` is the histogram of the positions of
the other points :math:`q` relative to it, in log-polar bins (Belongie et
al. 2002; in 3D, Frome et al. 2004):

- ``n_radial`` radial bins, log-spaced between ``r_inner`` and ``r_outer``
  times the mean distance between all pairs of points (so the descriptor is
  scale invariant); nearer points fall in the first bin, farther ones are
  left out;
- ``n_azimuth`` bins of the azimuth of :math:`q - p` about the z axis and
  ``n_elevation`` bins of equal solid angle (uniform in the z component of
  the unit direction).

The angles are measured in the global frame of the input, which is
meaningful because the inputs are pre-aligned to their principal axes
(:mod:`meshcorr.baselines.align`); Frome et al. use the surface normal as
the north pole and must then search over azimuth rotations. Histograms are
normalised to sum to one, and two are compared by the chi-square statistic

.. math::

    C(h, g) = \\frac12 \\sum_k \\frac{(h_k - g_k)^2}{h_k + g_k}.

Source and target samples are matched by a linear assignment on :math:`C`
(``scipy.optimize.linear_sum_assignment``; a source sample left over when
it has more points than the target takes its cheapest target), or by the
row-wise argmin.

Meshes larger than ``n_points`` are subsampled by farthest-point sampling
for the matching; every source vertex then moves by the displacement of its
nearest source sample (to that sample's match) and takes the nearest target
vertex.

References
----------
S. Belongie, J. Malik, J. Puzicha, "Shape matching and object recognition
using shape contexts", IEEE PAMI 24(4):509-522, 2002.
A. Frome, D. Huber, R. Kolluri, T. Bülow, J. Malik, "Recognizing objects in
range data using regional point descriptors", ECCV 2004.
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import linear_sum_assignment
from scipy.spatial import cKDTree
from scipy.spatial.distance import cdist

from ..runtime.checks import check_choice, check_float, check_int
from ..runtime.threads import kdtree_query
from ..core.mesh import MeshLike
from ..maps.result import Correspondence
from ..runtime.timing import StageProgress, StageTimer
from ..stages.tps import mean_pairwise_distance
from ._common import finish, load_pair, nearest_map, spatial_points
from .sampling import farthest_point_sample

ASSIGNMENTS = ("hungarian", "argmin")


def shape_context_histograms(points: np.ndarray, *, n_radial: int = 5, n_azimuth: int = 12,
                             n_elevation: int = 6, r_inner: float = 0.125, r_outer: float = 2.0,
                             random_state: int | None = 0) -> np.ndarray:
    """Normalised 3D shape-context histogram of every point (see the module docstring).

    Parameters
    ----------
    points : (n, 3) float
        The point set; each point's histogram counts the other points.
    n_radial, n_azimuth, n_elevation : int
        Bins per coordinate.
    r_inner, r_outer : float
        Inner and outer radius of the radial bins, in units of the mean
        distance between pairs of points (``0 < r_inner < r_outer``).
    random_state : int or None
        Seed of the sample that estimates the mean pairwise distance.

    Returns
    -------
    histograms : (n, n_radial * n_azimuth * n_elevation) float
        Each row sums to one (or is zero if no other point is in range).
    """
    n = len(points)
    unit = mean_pairwise_distance(points, random_state=random_state)
    edges = np.log(np.geomspace(r_inner, r_outer, n_radial + 1)[1:-1])
    n_bins = n_radial * n_azimuth * n_elevation
    counts = np.zeros((n, n_bins))
    step = max(1, 2_000_000 // max(1, n))
    for start in range(0, n, step):
        rows = np.arange(start, min(n, start + step))
        offset = points[None, :, :] - points[rows, None, :]
        distance = np.linalg.norm(offset, axis=2)
        valid = (distance > 0) & (distance <= r_outer * unit)
        safe = np.where(valid, distance, unit)  # the point itself and far points are dropped below
        radial = np.searchsorted(edges, np.log(safe / unit))
        z = np.clip(offset[..., 2] / safe, -1.0, 1.0)
        azimuth = np.arctan2(offset[..., 1], offset[..., 0])
        a_bin = np.minimum((azimuth + np.pi) / (2 * np.pi) * n_azimuth, n_azimuth - 1).astype(np.int64)
        e_bin = np.minimum((z + 1.0) / 2.0 * n_elevation, n_elevation - 1).astype(np.int64)
        bins = (radial * n_azimuth + a_bin) * n_elevation + e_bin
        owner = np.broadcast_to((rows - start)[:, None], bins.shape)
        block = np.zeros((len(rows), n_bins))
        np.add.at(block, (owner[valid], bins[valid]), 1.0)
        counts[rows] = block
    totals = counts.sum(axis=1, keepdims=True)
    return np.divide(counts, totals, out=np.zeros_like(counts), where=totals > 0)


def chi_square_cost(H: np.ndarray, G: np.ndarray) -> np.ndarray:
    """Chi-square cost between every pair of histograms.

    Parameters
    ----------
    H : (n1, b) float
    G : (n2, b) float

    Returns
    -------
    cost : (n1, n2) float
        :math:`\\frac12 \\sum_k (h_k - g_k)^2 / (h_k + g_k)`, empty bins of
        both skipped; in [0, 1] for normalised histograms.
    """
    # (h - g)^2 / (h + g) = (h + g) - 4 h g / (h + g): only the cross term needs pairs.
    cost = np.empty((len(H), len(G)))
    step = max(1, 4_000_000 // max(1, len(G) * H.shape[1]))
    for start in range(0, len(H), step):
        h = H[start:start + step, None, :]
        total = h + G[None, :, :]
        cross = np.divide(h * G[None, :, :], total, out=np.zeros_like(total), where=total > 0)
        cost[start:start + step] = 0.5 * (total.sum(axis=2) - 4.0 * cross.sum(axis=2))
    return cost


def match_histograms(cost: np.ndarray, assignment: str = "hungarian") -> np.ndarray:
    """Target column for every source row of a cost matrix.

    Parameters
    ----------
    cost : (n1, n2) float
    assignment : {"hungarian", "argmin"}
        Linear assignment (distinct columns while they last; rows left over
        take their cheapest column) or the row-wise argmin.

    Returns
    -------
    columns : (n1,) int
    """
    check_choice("assignment", assignment, ASSIGNMENTS)
    columns = np.argmin(cost, axis=1)
    if assignment == "hungarian":
        rows, cols = linear_sum_assignment(cost)
        columns[rows] = cols
    return columns


def match_shape_context(source: MeshLike, target: MeshLike, *, prealign: bool = True, n_points: int = 500,
                        n_radial: int = 5, n_azimuth: int = 12, n_elevation: int = 6, r_inner: float = 0.125,
                        r_outer: float = 2.0, assignment: str = "hungarian", bijective: bool = False,
                        largest_component: bool = False, random_state: int | None = 0,
                        progress: StageProgress | None = None) -> Correspondence:
    """Vertex map by 3D shape contexts.

    Parameters
    ----------
    source, target : path, trimesh.Trimesh, Mesh or (vertices, faces)
    prealign : bool
        Centre, scale and rotate each mesh to its principal axes first
        (:mod:`meshcorr.baselines.align`); the histograms' angular bins are
        in the global frame, so without it the inputs must already be aligned.
    n_points : int
        At most this many farthest-point samples of each mesh are described
        and matched (>= 10).
    n_radial, n_azimuth, n_elevation, r_inner, r_outer
        Histogram bins (see :func:`shape_context_histograms`).
    assignment : {"hungarian", "argmin"}
        How samples are matched (see :func:`match_histograms`).
    bijective : bool
        One-to-one final map by linear assignment on the moved vertices
        (equal vertex counts only).
    largest_component : bool
        Map only the largest connected component of each mesh.
    random_state : int or None
        Seed of the samples.
    progress : callable, optional
        ``progress(stage, done, total)``.

    Returns
    -------
    result : Correspondence
        ``method="shape-context"``; ``cost`` is the chi-square cost of the
        match of each vertex's nearest source sample.
    """
    n_points = check_int("n_points", n_points, minimum=10)
    for name, value in (("n_radial", n_radial), ("n_azimuth", n_azimuth), ("n_elevation", n_elevation)):
        check_int(name, value, minimum=1)
    r_inner = check_float("r_inner", r_inner, minimum=0.0, exclusive=True)
    r_outer = check_float("r_outer", r_outer, minimum=r_inner, exclusive=True)
    check_choice("assignment", assignment, ASSIGNMENTS)
    timer = StageTimer(progress)
    src, tgt = load_pair(source, target, largest_component=largest_component, timer=timer)
    P, Q = spatial_points(src, tgt, prealign=prealign, timer=timer)
    bins = dict(n_radial=n_radial, n_azimuth=n_azimuth, n_elevation=n_elevation, r_inner=r_inner,
                r_outer=r_outer, random_state=random_state)
    with timer.stage("descriptors"):
        sp = farthest_point_sample(P, n_points, random_state=random_state)
        sq = farthest_point_sample(Q, n_points, random_state=random_state)
        H, G = shape_context_histograms(P[sp], **bins), shape_context_histograms(Q[sq], **bins)
    with timer.stage("assignment"):
        cost = chi_square_cost(H, G)
        match = match_histograms(cost, assignment)
    with timer.stage("matching"):
        nearest_sample = kdtree_query(cKDTree(P[sp]), P)[1]
        moved = P + (Q[sq[match]] - P[sp])[nearest_sample]
        local_map, _ = nearest_map(moved, Q, bijective=bijective)
    params = dict(prealign=prealign, n_points=n_points, assignment=assignment, bijective=bijective,
                  largest_component=largest_component, **bins)
    local_cost = cost[np.arange(len(sp)), match][nearest_sample]
    return finish("shape-context", src, tgt, local_map, local_cost, timer, params)
