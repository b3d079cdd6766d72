"""Extremities of a shape and their matching: a global start that survives changes of proportion.

The spectral embedding's eigenvector configuration is chosen by how well
the two embeddings overlap, which fails when the proportions differ (a
gorilla's arms against a person's): the cheapest configurations then send
arms to legs. The tips of a shape (hands, feet, head, tail) are found
reliably on either shape and their *relative* geodesic distances change far
less than the embedding, so matching them gives candidate global
correspondences that do not depend on the embedding at all. This is the
classic extremity-based start of non-rigid matching (Zhang, Sheffer, Cohen-Or,
Zhou, Kraevoy & Liu, "Deformation-driven shape correspondence", SGP 2008;
Sahillioglu & Yemez, "Coarse-to-fine combinatorial matching for dense
isometric shape correspondence", SGP 2011).

**Extremities.** With ``m`` farthest-point samples :math:`s_t`, the average
geodesic distance :math:`\\mathrm{AGD}(v) = \\frac{1}{m} \\sum_t g(s_t, v)`
(Hilaga, Shinagawa, Kohmura & Kunii, "Topology matching for fully automatic
similarity estimation of 3D shapes", SIGGRAPH 2001) is largest at the tips.
Extremities are the vertices whose (three times one-ring averaged) AGD is the
largest of their two-ring and above the median, taken in decreasing AGD and
kept at least ``radius`` x sqrt(area) apart along the surface (non-maximum
suppression), at most ``max_count`` of them.

**Matching.** Every injective assignment :math:`\\pi` of ``p = min(m1, m2)``
extremities is scored by the distortion of their scale-normalised geodesic
distances (a small Gromov-Hausdorff / quadratic-assignment energy; Bronstein,
Bronstein & Kimmel, PNAS 2006),

.. math::

    E(\\pi) = \\frac{1}{p (p - 1)} \\sum_{a \\ne b}
        \\left| \\frac{D_1(a, b)}{\\bar D_1} - \\frac{D_2(\\pi a, \\pi b)}{\\bar D_2} \\right|,

with :math:`\\bar D` each shape's mean extremity distance. The left/right
swaps of a symmetric shape score alike; the caller tells them apart by the
orientation of the dense maps they lead to (:mod:`meshcorr.choice.selection`).
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass
from typing import Callable

import numpy as np
import scipy.sparse as sp

from ..core.sampling import farthest_point_sampling
from ..core.mesh import Mesh
from ..core.pointcloud import edges

RowFn = Callable[[int], np.ndarray]

#: Farthest-point samples over which the average geodesic distance is taken.
N_AGD_SAMPLES = 48
#: Least geodesic distance between two extremities, in units of sqrt(area).
EXTREMITY_RADIUS = 0.2
#: Most extremities kept per shape (assignments grow as max_count!).
MAX_EXTREMITIES = 8
#: Assignments beyond this many are not enumerated (see :func:`match_extremities`).
MAX_ASSIGNMENTS = 200_000


@dataclass(frozen=True)
class Extremities:
    """The tips of one shape.

    Attributes
    ----------
    vertices : (e,) int
        Extremity vertices, by decreasing average geodesic distance.
    distances : (e, n) float
        Geodesic distances from each extremity to every vertex (the units of
        the ``geodesics_from`` they came from).
    """

    vertices: np.ndarray
    distances: np.ndarray


def _one_ring(mesh: Mesh) -> sp.csr_matrix:
    """Adjacency of the mesh's edges (of a point cloud: its neighbour graph, :func:`meshcorr.core.pointcloud.edges`)."""
    pairs = edges(mesh.vertices, mesh.faces)
    adjacency = sp.coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(mesh.n_vertices,) * 2)
    return ((adjacency + adjacency.T) > 0).astype(np.float64).tocsr()


def find_extremities(mesh: Mesh, geodesics_from: RowFn, *, length_unit: float = 1.0,
                     n_samples: int = N_AGD_SAMPLES, radius: float = EXTREMITY_RADIUS,
                     max_count: int = MAX_EXTREMITIES, random_state: int | None = 0) -> Extremities:
    """Local maxima of the average geodesic distance, kept apart (module docstring).

    Parameters
    ----------
    mesh : Mesh
    geodesics_from : callable
        ``geodesics_from(i)`` returns the geodesic distances from vertex i, ``(n,)``.
    length_unit : float
        The length that ``geodesics_from`` reports as 1 (e.g. the largest
        geodesic distance), so that ``radius`` is in units of sqrt(area).
    n_samples : int
        Farthest-point samples of the AGD.
    radius : float
        Least distance between extremities, x sqrt(area).
    max_count : int
    random_state : int or None
        Seed of the first farthest-point sample.

    Returns
    -------
    extremities : Extremities
        At least one vertex (the AGD maximum).
    """
    n = mesh.n_vertices
    samples = farthest_point_sampling(geodesics_from, n, min(n_samples, n), random_state=random_state)
    agd = samples.distances.mean(axis=0)
    ring = _one_ring(mesh)
    degree = np.maximum(np.asarray(ring.sum(axis=1)).ravel(), 1.0)
    for _ in range(3):  # a little smoothing: a raw AGD has spurious one-vertex maxima on rough meshes
        agd = 0.5 * agd + 0.5 * (ring @ agd) / degree
    two_ring = ((ring @ ring + ring) > 0).tocsr()
    neighbour_max = np.maximum.reduceat(agd[two_ring.indices], two_ring.indptr[:-1])
    peaks = np.flatnonzero((agd >= neighbour_max) & (agd >= np.median(agd)))
    peaks = peaks[np.argsort(-agd[peaks], kind="stable")]
    separation = radius * np.sqrt(mesh.area) / length_unit
    chosen: list[int] = []
    rows: list[np.ndarray] = []
    for v in peaks:
        if rows and min(float(row[v]) for row in rows) < separation:
            continue
        chosen.append(int(v))
        rows.append(np.asarray(geodesics_from(int(v)), dtype=np.float64))
        if len(chosen) == max_count:
            break
    return Extremities(np.array(chosen, dtype=np.int64), np.array(rows))


def spectrum_extremities(mesh: Mesh, spectrum, *, random_state: int | None = 0) -> Extremities:
    """:func:`find_extremities` of a mesh with its spectrum's geodesics, computed once per spectrum.

    Parameters
    ----------
    mesh : Mesh
    spectrum : Spectrum
        Of ``mesh``; its ``geodesics_from`` and ``max_geodesic`` (the length unit).
    random_state : int or None

    Returns
    -------
    extremities : Extremities
        The same as ``find_extremities(mesh, spectrum.geodesics_from,
        length_unit=spectrum.max_geodesic, random_state=random_state)``: it
        depends on the shape only, so a prepared shape matched many times
        finds its tips once (kept in ``spectrum.memo``; read-only arrays).
    """
    if not isinstance(random_state, (int, np.integer)):  # an unseeded sample is drawn anew each time
        return find_extremities(mesh, spectrum.geodesics_from, length_unit=spectrum.max_geodesic,
                                random_state=random_state)
    key = ("extremities", int(random_state))
    if key not in spectrum.memo:
        tips = find_extremities(mesh, spectrum.geodesics_from, length_unit=spectrum.max_geodesic,
                                random_state=random_state)
        tips.vertices.flags.writeable = tips.distances.flags.writeable = False
        spectrum.memo[key] = tips
    return spectrum.memo[key]


def match_extremities(source: Extremities, target: Extremities, *, n_best: int = 4
                      ) -> list[tuple[float, np.ndarray]]:
    """The ``n_best`` injective extremity assignments of least distance distortion.

    Parameters
    ----------
    source, target : Extremities
    n_best : int

    Returns
    -------
    assignments : list of (energy, (p, 2) int)
        Increasing :math:`E(\\pi)` (module docstring); each array holds
        (source vertex, target vertex) pairs. Empty when either shape has
        fewer than three extremities (too few to constrain a map).
    """
    p = min(len(source.vertices), len(target.vertices))
    if p < 3:
        return []
    D1 = source.distances[:, source.vertices]
    D2 = target.distances[:, target.vertices]
    D1 = 0.5 * (D1 + D1.T) / max(D1.mean(), 1e-12)
    D2 = 0.5 * (D2 + D2.T) / max(D2.mean(), 1e-12)
    subsets = [np.array(s) for s in itertools.combinations(range(len(source.vertices)), p)]
    orders = np.array(list(itertools.permutations(range(len(target.vertices)), p)))
    if len(subsets) * len(orders) > MAX_ASSIGNMENTS:  # keep the strongest tips only
        return match_extremities(Extremities(source.vertices[:-1], source.distances[:-1]),
                                 Extremities(target.vertices[:-1], target.distances[:-1]), n_best=n_best)
    found = []
    for subset in subsets:
        A = D1[np.ix_(subset, subset)]
        B = D2[orders[:, :, None], orders[:, None, :]]  # (orders, p, p)
        energy = np.abs(B - A).sum(axis=(1, 2)) / (p * (p - 1))
        best = np.argsort(energy, kind="stable")[:n_best]
        found += [(float(energy[b]), subset, orders[b]) for b in best]
    found.sort(key=lambda item: item[0])
    return [(energy, np.stack([source.vertices[s], target.vertices[o]], axis=1))
            for energy, s, o in found[:n_best]]
