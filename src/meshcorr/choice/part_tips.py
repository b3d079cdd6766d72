"""The tips of a part away from its cut, and their assignment to the whole's tips by consensus.

The tips of a shape (:mod:`meshcorr.choice.extremities`) are found on a
part :math:`P` as on the whole :math:`W`, but a cut makes new maxima of the
average geodesic distance along it: :func:`part_extremities` keeps the
part's tips in its interior only (:func:`meshcorr.stages.part_cut.interior_vertices`),
:func:`whole_extremities` takes up to :data:`N_WHOLE_TIPS` of the whole's
(docs/method.md, "Partial shapes", steps 1-2). Tips of either side may have
no counterpart, and the scale between part and whole is unknown, so
:func:`match_part_tips` searches assignments by consensus over triangles of
tips (in the spirit of RANSAC, Fischler & Bolles 1981) and ranks them by
their number of tips, then by the distortion of their geodesic distances,
each side divided by its own sum,

.. math::

    E = \\frac{p}{p - 1} \\sum_{a \\ne b}
        \\left| \\frac{A_{ab}}{\\sum A} - \\frac{B_{\\pi a \\pi b}}{\\sum B} \\right| ;

the best :data:`N_ASSIGNMENTS` become candidate maps.
"""

from __future__ import annotations

import itertools

import numpy as np

from ..core.mesh import Mesh
from ..stages.part_checks import RowFn
from .extremities import MAX_EXTREMITIES, Extremities, find_extremities

#: Tip assignments turned into dense candidate maps (:func:`match_part_tips`).
N_ASSIGNMENTS = 6
#: Relative geodesic distance error under which a part tip and a whole tip agree.
TIP_TOLERANCE = 0.12
#: Tips of the whole shape considered.
N_WHOLE_TIPS = 10


def part_extremities(part: Mesh, rows: RowFn, interior: np.ndarray, *, random_state: int | None = 0
                     ) -> Extremities:
    """Tips of the part (:func:`meshcorr.choice.extremities.find_extremities`) that are not near its cut.

    Parameters
    ----------
    part : Mesh
    rows : callable
        Geodesic rows in the part's units (:func:`meshcorr.stages.part_checks.geodesic_rows`).
    interior : (p,) int
        Vertices away from the boundary (:func:`meshcorr.stages.part_cut.interior_vertices`).
    random_state : int or None

    Returns
    -------
    tips : Extremities
        At most :data:`~meshcorr.choice.extremities.MAX_EXTREMITIES`, by decreasing average geodesic distance.
    """
    tips = find_extremities(part, rows, length_unit=1.0, max_count=2 * MAX_EXTREMITIES, random_state=random_state)
    inside = np.zeros(part.n_vertices, dtype=bool)
    inside[interior] = True
    keep = np.flatnonzero(inside[tips.vertices])[:MAX_EXTREMITIES]
    return Extremities(tips.vertices[keep], tips.distances[keep])


def whole_extremities(whole: Mesh, rows: RowFn, *, random_state: int | None = 0) -> Extremities:
    """Up to :data:`N_WHOLE_TIPS` tips of the whole (:func:`meshcorr.choice.extremities.find_extremities`).

    ``rows`` are the whole's geodesic rows in its own units (:func:`meshcorr.stages.part_checks.geodesic_rows`).
    """
    return find_extremities(whole, rows, length_unit=1.0, max_count=N_WHOLE_TIPS, random_state=random_state)


def match_part_tips(part: Extremities, whole: Extremities, *, n_best: int = N_ASSIGNMENTS,
                    tolerance: float = TIP_TOLERANCE) -> list[tuple[float, np.ndarray]]:
    """The best assignments of the part's tips to the whole's, some tips left without counterpart.

    A consensus search over triangles (in the spirit of RANSAC, Fischler &
    Bolles 1981): every triangle of three part tips is put against every
    ordered triangle of whole tips whose side lengths agree with it up to
    the scale :math:`s = \\sum B / \\sum A` (relative error of the sides below
    ``tolerance``); each other part tip :math:`t` then joins the whole tip
    :math:`u` whose distances to the three whole corners are those of
    :math:`t` to the part's corners times :math:`s` (largest relative error
    below ``tolerance``, one whole tip per part tip, best first). The
    assignments with the most tips win, ties broken by the distortion of all
    their distances, each side normalised by its own sum (the scale between
    part and whole is unknown),

    .. math::

        E = \\frac{p}{p - 1} \\sum_{a \\ne b}
            \\left| \\frac{A_{ab}}{\\sum A} - \\frac{B_{\\pi a \\pi b}}{\\sum B} \\right|

    (the mean relative distortion of a tip's distances). Tips of the part
    with no counterpart (new maxima of the average geodesic distance that the
    cut made) and tips of the whole outside the part fall out of the
    consensus. Mirror-image assignments of a symmetric shape score alike; the
    dense maps' orientation tells them apart (:mod:`meshcorr.choice.selection`).

    Parameters
    ----------
    part, whole : Extremities
    n_best : int
        Distinct assignments returned.
    tolerance : float
        Relative distance error under which tips agree.

    Returns
    -------
    assignments : list of (energy, (p, 2) int)
        (part vertex, whole vertex) pairs, p >= 3, most tips first; empty
        when either shape has fewer than three tips.
    """
    m1, m2 = len(part.vertices), len(whole.vertices)
    if min(m1, m2) < 3:
        return []
    D1 = part.distances[:, part.vertices]
    D2 = whole.distances[:, whole.vertices]
    D1, D2 = 0.5 * (D1 + D1.T), 0.5 * (D2 + D2.T)
    tri1 = np.array(list(itertools.combinations(range(m1), 3)))
    tri2 = np.array(list(itertools.permutations(range(m2), 3)))
    sides = ([0, 1, 2], [1, 2, 0])
    A = D1[tri1[:, sides[0]], tri1[:, sides[1]]]  # (T1, 3)
    B = D2[tri2[:, sides[0]], tri2[:, sides[1]]]  # (T2, 3)
    scale = B.sum(axis=1)[None, :] / np.maximum(A.sum(axis=1)[:, None], 1e-300)  # (T1, T2)
    error = np.abs(A[:, None, :] * scale[:, :, None] - B[None, :, :]).max(axis=2) / np.maximum(
        B.mean(axis=1)[None, :], 1e-300)
    found: dict[tuple, tuple[float, np.ndarray]] = {}
    for i, j in zip(*np.nonzero(error < tolerance)):
        s, size = scale[i, j], B[j].mean()
        P = D1[:, tri1[i]] * s  # (m1, 3): every part tip's distances to the part triangle, whole units
        Q = D2[:, tri2[j]]  # (m2, 3): every whole tip's to the whole triangle
        cost = np.abs(P[:, None, :] - Q[None, :, :]).max(axis=2) / size  # (m1, m2)
        cost[tri1[i], :] = np.inf
        cost[:, tri2[j]] = np.inf
        pairs = list(zip(tri1[i].tolist(), tri2[j].tolist()))
        for flat in np.argsort(cost, axis=None, kind="stable"):
            a, b = divmod(int(flat), m2)
            if cost[a, b] >= tolerance:
                break
            if all(a != x and b != y for x, y in pairs):
                pairs.append((a, b))
        key = tuple(sorted(pairs))
        if key not in found:
            found[key] = (_tip_energy(D1, D2, np.array(key)), np.array(key))
    ranked = sorted(found.values(), key=lambda item: (-len(item[1]), item[0]))[:n_best]
    return [(energy, np.stack([part.vertices[k[:, 0]], whole.vertices[k[:, 1]]], axis=1)) for energy, k in ranked]


def _tip_energy(D1: np.ndarray, D2: np.ndarray, pairs: np.ndarray) -> float:
    """E of :func:`match_part_tips` for (part tip, whole tip) index pairs."""
    p = len(pairs)
    A = D1[np.ix_(pairs[:, 0], pairs[:, 0])]
    B = D2[np.ix_(pairs[:, 1], pairs[:, 1])]
    return float(np.abs(A / max(A.sum(), 1e-300) - B / max(B.sum(), 1e-300)).sum() * p * p / (p - 1))
