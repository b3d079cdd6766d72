"""Matching a part of a shape to the whole shape (``match(..., partial="source")``).

A scan seen from one side, a body cut by the field of view or a surface with
large holes is a *part* :math:`P` of a whole shape :math:`W`. The global steps
of the whole-to-whole pipeline do not hold on a part: the Jain-Zhang
affinities are scaled by the largest geodesic distance and their
eigenvectors are global, so the part's embedding is not the restriction of
the whole's (a TOSCA cat cut to 70 % maps onto the whole cat with a mean
error of 0.1-0.6 instead of 0.03); and the part's Laplace-Beltrami spectrum
is "stretched": its first :math:`k` eigenfunctions correspond to about the
first :math:`k / r` of the whole's, :math:`r = \\operatorname{area}(P) /
\\operatorname{area}(W)` in common units (Rodolà, Cosmo, Bronstein, Torsello
& Cremers, "Partial functional correspondence", Computer Graphics Forum 36(1),
2017: the functional map of a part is slanted-diagonal with that slope).
What does hold is that geodesic distances between points of the part away
from its cut are (nearly) those of the whole. The partial mode is built on
that:

1. **Extremities** (:mod:`meshcorr.choice.extremities`): the tips of the whole, and
   those of the part that lie farther than :data:`BOUNDARY_BAND` x
   sqrt(area(P)) from its boundary (a cut makes new maxima of the average
   geodesic distance along it).
2. **Tip assignments** (:func:`match_part_tips`): a consensus search over
   triangles of tips (after RANSAC): each triangle of the part's tips
   against each triangle of the whole's whose sides agree up to a common
   scale, the other tips joining where their distances agree too (tips of
   either side may have no counterpart); the assignments with the most tips
   win, ties broken by the distortion of their geodesic distances, each
   side divided by its own sum (the scale between part and whole is
   unknown).
3. **Dense maps** (:func:`part_landmark_map`): each assignment becomes a map by
   nearest geodesic-distance descriptors, then
   :func:`geodesic_refine` re-takes :data:`N_REFINE_LANDMARKS`
   farthest-point landmarks away from the boundary with their current images
   and maps again: a few well-spread landmarks fix the map far better than
   the few tips do.
4. **The choice** (:mod:`meshcorr.choice.selection`): orientation (a part of a
   closed shape has a well-defined outside once its boundary loops are
   capped, :mod:`meshcorr.core.orientation`), curvature disagreement and the
   metric distortion of :func:`fitted_distortion`, which fits the unknown
   scale and leaves out the vertices near the cut.
5. **Partial ZoomOut** (:func:`partial_zoomout`): the chosen map is refined
   in Laplace-Beltrami bases of :math:`k` functions on the part and
   :math:`\\lceil k / r \\rceil` on the whole, :math:`r` the area fraction of
   the matched region, with a rectangular functional map whose rows are
   orthonormal up to a common scale (the slanted-diagonal structure above
   gives :math:`C C^\\top \\approx I / r`), and with the whole's vertices
   restricted to the matched region (the part's "indicator function" of
   Rodolà et al., here estimated from the map instead of optimised). Vertices
   near the cut are weighted down in every fit.
6. **Smooth shells** (:func:`meshcorr.stages.shells.shell_refine` with
   ``part_fraction``): the part's shells aligned with the whole's, from 16
   functions on the part (and :math:`\\lceil k / r \\rceil` on the whole) to
   the coordinates themselves, the whole's vertices restricted to the
   region matched by the zoomed-out map and the cut weighted down as above
   (meshes only).
7. **The matched region** (:func:`matched_region`): the whole's vertices
   reached by the map, joined by a morphological closing along the surface,
   reported as a vertex mask and its area fraction.

Litany, Rodolà, Bronstein & Bronstein ("Fully spectral partial shape
matching", Computer Graphics Forum 36(2), 2017) solve for the part's basis
jointly with the map; that optimisation is not used here.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass, field
from math import ceil
from typing import Sequence

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import dijkstra
from scipy.spatial import cKDTree

from ..runtime.threads import parallel_map
from ..core.boundary import boundary_distance
from ..errors import PartialityError
from ..choice.extremities import MAX_EXTREMITIES, Extremities, find_extremities
from ..core.sampling import farthest_point_sampling
from ..core.mesh import Mesh
from ..core.orientation import mesh_orientation, vertex_normals
from ..spectral.basis import laplace_basis
from ..spectral.nearest import nearest_rows
from ..choice.selection import LANDMARK_RADIUS, MapCandidate, candidate_summaries, choose_map, score_orientation
from ..stages.shells import shell_refine
from ..runtime.timing import StageTimer
from ..stages.part_checks import RowFn, geodesic_rows


#: Vertices of the part closer than this x sqrt(area of the part) to its boundary are "near the cut".
BOUNDARY_BAND = 0.08
#: Tip assignments turned into dense candidate maps (:func:`match_part_tips`).
N_ASSIGNMENTS = 6
#: Relative geodesic distance error under which a part tip and a whole tip agree.
TIP_TOLERANCE = 0.12
#: Tips of the whole shape considered.
N_WHOLE_TIPS = 10
#: Farthest-point landmarks of :func:`geodesic_refine`, its rounds, and the share of
#: least consistent landmarks it leaves out each round.
N_REFINE_LANDMARKS = 24
REFINE_ROUNDS = 3
REFINE_DROP = 0.2
#: Source vertices whose geodesic rows measure a candidate's distortion.
N_DISTORTION_SOURCES = 16
#: Radius of the closing that joins the matched region, x sqrt(area of the whole).
REGION_CLOSING = 0.03

@dataclass
class PartialMap:
    """The outcome of :func:`match_part`.

    Attributes
    ----------
    mapping : (n_part,) int
        Whole vertex of each part vertex (local numbering).
    alternative : (n_part,) int or None
        The best candidate of the other orientation (usually the mirror image).
    region : (n_whole,) bool
        The whole's vertices with a counterpart on the part.
    area_fraction : float
        Area of ``region`` over the whole's area.
    scale : float
        Whole length per part length, fitted to the geodesic distances of the map.
    candidates : list of dict
        Each candidate map's origin and scores (:class:`meshcorr.choice.selection.MapCandidate`).
    reliable : bool
        Whether the orientation of both meshes could be trusted.
    history : list of dict
        Per partial ZoomOut iteration: basis sizes and the fraction of samples whose image changed.
    """

    mapping: np.ndarray
    alternative: np.ndarray | None
    region: np.ndarray
    area_fraction: float
    scale: float
    candidates: list = field(default_factory=list)
    reliable: bool = True
    history: list = field(default_factory=list)



def interior_vertices(part: Mesh, *, band: float = BOUNDARY_BAND) -> np.ndarray:
    """``(p,)`` int: the vertices farther than ``band`` x sqrt(area) from the boundary.

    All vertices when fewer than a tenth of them are that far (a thin strip).
    """
    far = np.flatnonzero(boundary_distance(part) > band * np.sqrt(part.area))
    return far if len(far) >= max(10, part.n_vertices // 10) else np.arange(part.n_vertices)


def part_extremities(part: Mesh, rows: RowFn, interior: np.ndarray, *, random_state: int | None = 0
                     ) -> Extremities:
    """Tips of the part (:func:`meshcorr.choice.extremities.find_extremities`) that are not near its cut.

    Parameters
    ----------
    part : Mesh
    rows : callable
        Geodesic rows in the part's units (:func:`geodesic_rows`).
    interior : (p,) int
        Vertices away from the boundary (:func:`interior_vertices`).
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
        Geodesic rows (:func:`geodesic_rows`).
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
        Geodesic rows (:func:`geodesic_rows`).
    mapping : (n_part,) int
        Current map.
    interior : (p,) int
        Where landmarks may lie (:func:`interior_vertices`).
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


def fitted_distortion(part_rows: RowFn, whole_rows: RowFn, mapping: np.ndarray, sources: np.ndarray,
                      interior: np.ndarray) -> tuple[float, float]:
    """Metric distortion of a part -> whole map with the scale fitted, and that scale.

    With :math:`g_P` and :math:`g_W` the geodesic distances from the ``sources``
    to the ``interior`` vertices and between their images,

    .. math::

        s^* = \\arg\\min_s \\sum |g_P - s \\, g_W|, \\qquad
        \\text{distortion} = \\frac{\\operatorname{mean} |g_P - s^* g_W|}{\\operatorname{mean} g_P}

    (a weighted median; Bronstein, Bronstein & Kimmel, PNAS 2006, for the
    distortion). Vertices near the cut are left out: their distances on the
    part can be longer than on the whole, the shortcut through the missing
    region being gone.

    Returns
    -------
    distortion : float
        About 0 for an isometric map, near 1 for a map that collapses.
    scale : float
        :math:`1 / s^*`: whole length per part length.
    """
    gp = np.concatenate([part_rows(int(i))[interior] for i in sources])
    gw = np.concatenate([whole_rows(int(mapping[i]))[mapping[interior]] for i in sources])
    ok = gw > 0
    if not ok.any():
        return 1.0, 1.0
    ratio = gp[ok] / gw[ok]
    order = np.argsort(ratio, kind="stable")
    weights = np.cumsum(gw[ok][order])
    s = float(ratio[order][np.searchsorted(weights, 0.5 * weights[-1])])
    return float(np.abs(gp - s * gw).mean() / max(gp.mean(), 1e-300)), 1.0 / max(s, 1e-300)


def _edge_graph(mesh: Mesh) -> sp.csr_matrix:
    """Edge lengths of ``mesh`` as a symmetric sparse matrix, cached."""
    key = ("edge_graph",)
    if key not in mesh.store:
        f = mesh.faces
        e = np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]])
        lengths = np.linalg.norm(mesh.vertices[e[:, 0]] - mesh.vertices[e[:, 1]], axis=1)
        n = mesh.n_vertices
        graph = sp.coo_matrix((lengths, (e[:, 0], e[:, 1])), shape=(n, n)).tocsr()
        mesh.store.put(key, graph.maximum(graph.T).tocsr())
    return mesh.store[key]


def mean_edge_length(mesh: Mesh) -> float:
    """Mean edge length of ``mesh``."""
    return float(_edge_graph(mesh).data.mean())


def matched_region(whole: Mesh, images: np.ndarray, *, reach: float, closing: float) -> np.ndarray:
    """``(n_whole,)`` bool: the whole's vertices that the map reaches, joined by a closing.

    The vertices within ``reach`` (along the edges, multi-source Dijkstra) of
    an image are dilated by ``closing`` and eroded by as much again: gaps
    narrower than about twice ``closing`` between images are filled (a
    vertex map is not onto), the outline does not grow.

    Parameters
    ----------
    whole : Mesh
    images : (p,) int
        Whole vertices the part maps to.
    reach, closing : float
        Lengths in the whole's units.
    """
    graph = _edge_graph(whole)
    near = dijkstra(graph, directed=False, indices=np.unique(images), min_only=True, limit=reach + closing)
    dilated = np.isfinite(near)
    outside = np.flatnonzero(~dilated)
    if len(outside) == 0:
        return dilated
    back = dijkstra(graph, directed=False, indices=outside, min_only=True, limit=closing)
    return dilated & ~np.isfinite(back) | (np.isfinite(near) & (near <= reach))


def partial_zoomout(part_basis: np.ndarray, whole_basis: np.ndarray, mapping: np.ndarray, *, ratio: float,
                    allowed: np.ndarray | None = None, weights: np.ndarray | None = None, k_start: int = 16,
                    step: int = 2, n_sample: int = 500, random_state: int | None = 0
                    ) -> tuple[np.ndarray, list[dict]]:
    """Refine a part -> whole map by ZoomOut with a rectangular functional map (module docstring).

    For :math:`k = k_0, k_0 + s, \\dots, K` with :math:`k_W = \\lceil k / r \\rceil`,

    .. math::

        C = \\sigma U V^\\top, \\quad U \\Sigma V^\\top = A^\\top W B, \\qquad
        T(i) = \\arg\\min_{j \\in R} \\lVert \\Phi_P^{(k)}(i) - \\Phi_W^{(k_W)}(j) C^\\top / \\sigma \\rVert

    with :math:`A = \\Phi_P^{(k)}[S]` and :math:`B = \\Phi_W^{(k_W)}[T(S)]` on a
    seeded sample :math:`S` of the part, :math:`W` the vertex weights,
    :math:`\\sigma` the least-squares scale of :math:`A U V^\\top \\approx B`
    (about :math:`1 / \\sqrt r`), and :math:`R` the allowed whole vertices.
    The search runs in the part's :math:`k` dimensions, the whole's
    functions projected by :math:`C^\\top`: functions of the whole beyond the
    part's reach are projected away instead of adding noise.

    Parameters
    ----------
    part_basis : (n_p, K) float
    whole_basis : (n_w, K_W) float
        :math:`K_W \\ge \\lceil K / r \\rceil` (fewer are used if not).
    mapping : (n_p,) int
        Initial map.
    ratio : float
        r, the part's area fraction of the whole, in (0, 1].
    allowed : (n_w,) bool, optional
        Whole vertices the map may reach (default all).
    weights : (n_p,) float, optional
        Weight of each part vertex in the fits (default 1).
    k_start, step, n_sample, random_state
        As :func:`meshcorr.stages.refine.zoomout`.

    Returns
    -------
    mapping : (n_p,) int
    history : list of dict
        ``k``, ``k_whole`` and ``changed`` (fraction of the sampled part vertices whose image changed).
    """
    K, K_whole = part_basis.shape[1], whole_basis.shape[1]
    n1, n2 = len(part_basis), len(whole_basis)
    pool = np.arange(n2) if allowed is None else np.flatnonzero(allowed)
    rng = np.random.default_rng(random_state)
    s1 = np.arange(n1) if n1 <= n_sample else np.sort(rng.choice(n1, size=n_sample, replace=False))
    s2 = pool if len(pool) <= n_sample else np.sort(rng.choice(pool, size=n_sample, replace=False))
    w = np.ones(len(s1)) if weights is None else np.asarray(weights, dtype=float)[s1]
    images = np.asarray(mapping, dtype=np.int64)[s1]
    history: list[dict] = []
    projection = None
    for k in list(range(min(k_start, K), K, step)) + [K]:
        kw = min(K_whole, int(ceil(k / ratio)))
        A, B = part_basis[s1, :k], whole_basis[images, :kw]
        U, S, Vt = np.linalg.svd((A * w[:, None]).T @ (B * w[:, None]), full_matrices=False)
        projection = (U @ Vt).T  # (kw, k): C^T / sigma
        new = s2[nearest_rows(A, whole_basis[s2, :kw] @ projection)]
        history.append({"k": int(k), "k_whole": int(kw), "changed": float(np.mean(new != images))})
        images = new
    kw = projection.shape[0]
    return pool[nearest_rows(part_basis, whole_basis[pool, :kw] @ projection)], history


def _orientation_reliable(*meshes: Mesh) -> bool:
    return all(mesh_orientation(mesh).reliable for mesh in meshes)


def match_part(part: Mesh, whole: Mesh, part_rows: RowFn, whole_rows: RowFn, *, landmarks: np.ndarray | None = None,
               extremities: bool = True, initial_maps: Sequence[tuple[str, np.ndarray]] = (), refine: bool = True,
               refine_k: int = 40, shells: bool = True, random_state: int | None = 0,
               timer: StageTimer | None = None) -> PartialMap:
    """Map a part of a shape into the whole shape (module docstring, steps 1-7).

    Parameters
    ----------
    part, whole : Mesh
    part_rows, whole_rows : callable
        Geodesic rows of each in its own units (:func:`geodesic_rows`).
    landmarks : (L, 2) int, optional
        Known (part vertex, whole vertex) pairs: a candidate map of their own,
        decisive in the choice (:mod:`meshcorr.choice.selection`).
    extremities : bool
        Start candidate maps from matched tips.
    initial_maps : sequence of (str, (n_part,) int)
        Further starts, named (e.g. the map of the part matched as a whole
        shape, which holds when the cut leaves the shape's global structure).
    refine : bool
        Finish with :func:`partial_zoomout`.
    refine_k : int
        Its basis size on the part.
    shells : bool
        Then align the part's smooth shells with the whole's
        (:func:`meshcorr.stages.shells.shell_refine` with ``part_fraction``; meshes
        only, stage "shells").
    random_state : int or None
    timer : StageTimer, optional
        Receives the stages "extremities", "candidates", "refine", "shells" and "region".

    Returns
    -------
    result : PartialMap

    Raises
    ------
    PartialityError
        No candidate map: fewer than three tips of the part could be assigned and no landmarks.
    """
    timer = timer or StageTimer()
    with timer.stage("extremities"):
        interior = interior_vertices(part)
        starts: list[tuple[str, np.ndarray | None, np.ndarray | None, dict]] = []
        if landmarks is not None:
            starts.append(("landmarks", landmarks, None, {}))
        starts += [(origin, None, np.asarray(mapping, dtype=np.int64), {}) for origin, mapping in initial_maps]
        if extremities:
            tips = part_extremities(part, part_rows, interior, random_state=random_state)
            whole_tips = find_extremities(whole, whole_rows, length_unit=1.0, max_count=N_WHOLE_TIPS,
                                          random_state=random_state)
            for rank, (energy, pairs) in enumerate(match_part_tips(tips, whole_tips)):
                starts.append((f"extremities-{rank}", pairs, None,
                               {"extremity_energy": energy, "n_tips": len(pairs)}))
    if not starts:
        raise PartialityError(
            f"No start for a partial map of {part.name!r}: fewer than three of its tips lie away from its "
            "boundary. Give a few corresponding vertices (landmarks=[(i, j), ...], CLI --landmarks).")
    with timer.stage("candidates"):
        reliable = _orientation_reliable(part, whole)
        candidates = [_candidate(origin, pairs, start, extra, part, whole, part_rows, whole_rows, interior,
                                 landmarks, reliable=reliable, random_state=random_state)
                      for origin, pairs, start, extra in starts]
        chosen, alternative = choose_map(candidates, reliable=reliable)
        mapping, scale = chosen.mapping, chosen.extra.pop("scale")
        for candidate in candidates:
            candidate.extra.pop("scale", None)
    history: list[dict] = []
    if refine:
        with timer.stage("refine"):
            region, ratio = _matched_share(part, whole, mapping, scale)
            k = min(refine_k, part.n_vertices - 1)
            k_whole = min(int(ceil(k / ratio)), whole.n_vertices - 1)
            part_basis, whole_basis = parallel_map(
                lambda item: laplace_basis(item[0], item[1], random_state=random_state)[1],
                ((part, k), (whole, k_whole)))
            weights = np.clip(boundary_distance(part) / (BOUNDARY_BAND * np.sqrt(part.area)), 0.1, 1.0)
            mapping, history = partial_zoomout(part_basis, whole_basis, mapping, ratio=ratio, allowed=region,
                                               weights=weights, random_state=random_state)
            if landmarks is not None:
                mapping[landmarks[:, 0]] = landmarks[:, 1]
        if shells and not (part.is_cloud or whole.is_cloud):
            with timer.stage("shells"):  # in the region of the zoomed-out map, with the same weights
                region, ratio = _matched_share(part, whole, mapping, scale)
                mapping = shell_refine(part, whole, mapping, k=k, landmarks=landmarks, part_fraction=ratio,
                                       region=region, weights=weights, random_state=random_state)
    with timer.stage("region"):
        _, scale = fitted_distortion(part_rows, whole_rows, mapping, _sources(interior, random_state), interior)
        region = part_region(part, whole, mapping, scale)
    summaries = candidate_summaries(candidates, chosen, alternative, reliable=reliable)
    return PartialMap(mapping=mapping, alternative=None if alternative is None else alternative.mapping,
                      region=region, area_fraction=_area_fraction(whole, region), scale=scale,
                      candidates=summaries, reliable=reliable, history=history)


def _sources(interior: np.ndarray, random_state) -> np.ndarray:
    """The seeded interior vertices whose geodesic rows measure distortion and scale."""
    rng = np.random.default_rng(random_state)
    return rng.choice(interior, size=min(N_DISTORTION_SOURCES, len(interior)), replace=False)


def _candidate(origin: str, pairs: np.ndarray | None, start: np.ndarray | None, extra: dict, part: Mesh,
               whole: Mesh, part_rows: RowFn, whole_rows: RowFn, interior: np.ndarray,
               landmarks: np.ndarray | None, *, reliable: bool, random_state) -> MapCandidate:
    """One candidate map from landmark pairs or a start map (steps 3-4 of the module docstring), scored."""
    if start is None:
        start, _ = part_landmark_map(part_rows, whole_rows, pairs)
    mapping = geodesic_refine(part_rows, whole_rows, start, interior, random_state=random_state)
    if origin == "landmarks":
        mapping[pairs[:, 0]] = pairs[:, 1]
    candidate = MapCandidate(origin, mapping, extra=dict(extra))
    candidate.distortion, candidate.extra["scale"] = fitted_distortion(
        part_rows, whole_rows, mapping, _sources(interior, random_state), interior)
    if reliable:
        score_orientation(candidate, part, whole, random_state=random_state)
    if landmarks is not None:
        rows = [whole_rows(int(b)) for b in landmarks[:, 1]]
        errors = np.array([row[mapping[a]] for row, a in zip(rows, landmarks[:, 0])])
        diameter = max(float(row.max()) for row in rows)
        candidate.landmark_error = float(errors.mean() / diameter)
        candidate.landmarks_kept = float(np.mean(errors <= LANDMARK_RADIUS * diameter))
    return candidate


def part_region(part: Mesh, whole: Mesh, mapping: np.ndarray, scale: float) -> np.ndarray:
    """:func:`matched_region` of a part -> whole map with the module's reach and closing."""
    return matched_region(whole, mapping, reach=_reach(part, whole, scale),
                          closing=REGION_CLOSING * np.sqrt(whole.area))


def invert_part_map(whole: Mesh, mapping: np.ndarray, region: np.ndarray) -> np.ndarray:
    """A whole -> part map from a part -> whole one, defined on the matched region only.

    Parameters
    ----------
    whole : Mesh
    mapping : (n_part,) int
        Whole vertex of each part vertex.
    region : (n_whole,) bool
        The matched region (:func:`matched_region`).

    Returns
    -------
    inverse : (n_whole,) int
        For a vertex of the region, the part vertex whose image is nearest
        to it in space (itself where it is an image); -1 outside.
    """
    inverse = np.full(whole.n_vertices, -1, dtype=np.int64)
    inside = np.flatnonzero(region)
    if len(inside):
        inverse[inside] = cKDTree(whole.vertices[mapping]).query(whole.vertices[inside])[1]
    return inverse


def _reach(part: Mesh, whole: Mesh, scale: float) -> float:
    """How far around an image the whole counts as reached: 1.5 x the coarser of the two vertex spacings."""
    return 1.5 * max(mean_edge_length(whole), scale * mean_edge_length(part))


def _matched_share(part: Mesh, whole: Mesh, mapping: np.ndarray, scale: float) -> tuple[np.ndarray, float]:
    """The region of the whole a map reaches (:func:`part_region`) and its area fraction r, clipped to
    [0.2, 1]: the region and r of the refinements (:func:`partial_zoomout`, the part's smooth shells)."""
    region = part_region(part, whole, mapping, scale)
    return region, float(np.clip(_area_fraction(whole, region), 0.2, 1.0))


def _area_fraction(mesh: Mesh, mask: np.ndarray) -> float:
    _, areas = vertex_normals(mesh.vertices, mesh.faces)
    return float(areas[mask].sum() / areas.sum())


