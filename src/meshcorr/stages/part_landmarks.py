"""Dense part -> whole maps from geodesic landmarks: from landmark pairs, then from many spread landmarks.

A part :math:`P` keeps the geodesic distances of the whole :math:`W` away
from its cut (docs/method.md, "Partial shapes", step 3), up to an unknown
scale. A few landmark pairs :math:`(a_l, b_l)` (matched tips, user
landmarks) give a first map by nearest descriptors, each side normalised by
the mean distance between its own landmarks (:func:`part_landmark_map`; the
part lacks some of the whole's vertices, so the mean over all vertices of
:mod:`meshcorr.stages.landmarks` would not do):

.. math::

    T(i) = \\arg\\min_j \\left\\lVert \\frac{g_P(a, i)}{\\bar g_P(a, a)}
    - \\frac{g_W(b, j)}{\\bar g_W(b, b)} \\right\\rVert .

:func:`geodesic_refine` then re-takes :data:`N_REFINE_LANDMARKS`
farthest-point landmarks of the part's interior with their current images,
:data:`REFINE_ROUNDS` rounds, leaving out the :data:`REFINE_DROP` share
whose distances agree least: a few tips fix the map only near themselves,
many landmarks fix it everywhere.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from ..core.sampling import farthest_point_sampling
from .part_checks import RowFn

#: Farthest-point landmarks of :func:`geodesic_refine`, its rounds, and the share of
#: least consistent landmarks it leaves out each round.
N_REFINE_LANDMARKS = 24
REFINE_ROUNDS = 3
REFINE_DROP = 0.2


def part_landmark_map(part_rows: RowFn, whole_rows: RowFn, pairs: np.ndarray) -> tuple[np.ndarray, float]:
    """Dense part -> whole map from landmark pairs, and the scale it implies.

    Each vertex is described by its geodesic distances to the landmarks of
    its shape divided by the mean distance between those landmarks (the
    scale-free descriptors of :mod:`meshcorr.stages.landmarks`, normalised over
    the landmarks only, since the part lacks some of the whole's vertices),
    and mapped to the whole vertex of nearest descriptor (a KD-tree query).

    Parameters
    ----------
    part_rows, whole_rows : callable
        Geodesic rows (:func:`meshcorr.stages.part_checks.geodesic_rows`).
    pairs : (L, 2) int
        (part vertex, whole vertex), L >= 2.

    Returns
    -------
    mapping : (n_part,) int
        Landmarks go exactly to their partners.
    scale : float
        Mean landmark distance on the whole over that on the part.
    """
    pairs = np.asarray(pairs, dtype=np.int64)
    F1 = np.array([part_rows(int(a)) for a in pairs[:, 0]]).T
    F2 = np.array([whole_rows(int(b)) for b in pairs[:, 1]]).T
    u1 = max(float(F1[pairs[:, 0]].mean()), 1e-300)
    u2 = max(float(F2[pairs[:, 1]].mean()), 1e-300)
    mapping = cKDTree(F2 / u2).query(F1 / u1)[1].astype(np.int64)
    mapping[pairs[:, 0]] = pairs[:, 1]
    return mapping, u2 / u1


def geodesic_refine(part_rows: RowFn, whole_rows: RowFn, mapping: np.ndarray, interior: np.ndarray, *,
                    n_landmarks: int = N_REFINE_LANDMARKS, rounds: int = REFINE_ROUNDS,
                    drop: float = REFINE_DROP, random_state: int | None = 0) -> np.ndarray:
    """Re-map from many spread landmarks and their current images, a few rounds.

    The landmarks :math:`l_1 .. l_L` are geodesic farthest-point samples of
    the interior (seeded). Each round takes their images :math:`f(l)` under
    the current map, the scale :math:`s` = the median ratio of their
    distances on the whole to those on the part, and leaves out the
    ``drop`` share of landmarks whose distances to the others agree least
    (:math:`\\sum_m |s D_P(l, l_m) - D_W(f(l), f(l_m))|`: a landmark sent
    to the wrong place); each part vertex then goes to the whole vertex of
    nearest descriptor :math:`(s \\, g_P(l, i))_l` against
    :math:`(g_W(f(l), j))_l`, in the L1 norm (a few wrong distances, e.g.
    across a hole of the part, weigh less than in L2). A few tips fix the
    map only near themselves; many landmarks fix it everywhere.

    Parameters
    ----------
    part_rows, whole_rows : callable
        Geodesic rows (:func:`meshcorr.stages.part_checks.geodesic_rows`).
    mapping : (n_part,) int
        Current map.
    interior : (p,) int
        Where landmarks may lie (:func:`meshcorr.stages.part_cut.interior_vertices`).
    n_landmarks, rounds : int
    drop : float
        Share of landmarks left out each round, in [0, 1).
    random_state : int or None
        Seed of the first landmark.

    Returns
    -------
    mapping : (n_part,) int
    """
    n_landmarks = min(n_landmarks, len(interior))
    samples = farthest_point_sampling(lambda i: part_rows(int(interior[i]))[interior], len(interior),
                                      n_landmarks, random_state=random_state)
    landmarks = interior[samples.indices]
    R1 = np.array([part_rows(int(a)) for a in landmarks])  # (L, n_part)
    D1 = R1[:, landmarks]
    off = ~np.eye(len(landmarks), dtype=bool)
    for _ in range(rounds):
        images = mapping[landmarks]
        R2 = np.array([whole_rows(int(b)) for b in images])  # (L, n_whole)
        D2 = R2[:, images]
        s = float(np.median(D2[off] / np.maximum(D1[off], 1e-300)))
        disagreement = (np.abs(s * D1 - D2) * off).sum(axis=1)
        use = np.argsort(disagreement, kind="stable")[:max(3, int(round((1 - drop) * len(landmarks))))]
        new = cKDTree(R2[use].T).query(s * R1[use].T, p=1)[1].astype(np.int64)
        if np.array_equal(new, mapping):
            break
        mapping = new
    return mapping
