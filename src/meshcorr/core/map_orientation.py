"""The orientation a vertex map keeps: its orientation score, by region and per vertex.

An intrinsic symmetry (left/right of a person or an animal) is an isometry
that *reverses* orientation, so a map and its mirror image cost the same to
every intrinsic criterion, the spectral cost included (docs/method.md,
"Departures from the paper", the left/right mirror). Orientation tells them apart: with both meshes oriented
outwards, a correct map takes a small counter-clockwise loop around a
source vertex to a counter-clockwise loop around its image, a mirrored map
to a clockwise one.

The score of a vertex map :math:`f` is measured on mapped neighbourhoods.
For a source vertex :math:`i` with outward normal :math:`n_i` and a
right-handed tangent frame :math:`(u_i, v_i)`, :math:`u_i \\times v_i = n_i`,
its ``n_neighbors`` nearest vertices :math:`j` give tangent coordinates
:math:`a_j = ((x_j - x_i) \\cdot u_i, (x_j - x_i) \\cdot v_i)`; the least
squares Jacobian of :math:`f` at :math:`i` pushes :math:`u_i, v_i` to

.. math::

    (c_1, c_2) = \\sum_j (y_{f(j)} - y_{f(i)}) \\, a_j^T
                 \\left(\\sum_j a_j a_j^T\\right)^{-1}

and the map keeps the orientation at :math:`i` when the triple product
:math:`m_{f(i)} \\cdot (c_1 \\times c_2) > 0`, with :math:`m` the target's
outward vertex normal (the positive factor :math:`\\det(\\sum a a^T)^{-1}` is
left out: only the sign counts). The score is the area-weighted fraction of
sampled source vertices whose sign is positive, among those whose
neighbourhood does not collapse onto one target vertex: near 1 for an
orientation-preserving map, near 0 for a mirrored one, near 0.5 for noise.
Using a neighbourhood rather than single triangles makes the test robust to
the vertex-level noise of a nearest-neighbour map.

The normals and areas are those of :mod:`meshcorr.core.orientation`; a
point cloud's are estimated there, and the score is then the same.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from ..errors import ParameterError
from ..runtime.checks import check_int
from .mesh import Mesh
from .orientation import oriented_normals, tangent_frames
from .sampling import farthest_point_sampling


def _neighbourhoods(source: Mesh, n_neighbors: int, n_sample: int, random_state) -> tuple:
    """The map-independent part of :func:`orientation_score`, cached on the source mesh.

    Returns the sampled vertices ``(s,)``, their ``K`` nearest vertices
    ``(s, K)``, the neighbours' tangent coordinates ``a`` ``(s, K, 2)`` and the
    sampled vertices' areas ``(s,)``.
    """
    # Only a seeded sample is the same every time (random_state=None draws anew).
    seeded = isinstance(random_state, (int, np.integer))
    key = ("orientation_neighbourhoods", n_neighbors, n_sample, int(random_state) if seeded else None)
    if not seeded or key not in source.store:
        X = source.vertices
        src_normals, src_areas = oriented_normals(source)
        rng = np.random.default_rng(random_state)
        n1 = len(X)
        sample = np.arange(n1) if n1 <= n_sample else np.sort(rng.choice(n1, size=n_sample, replace=False))
        k = min(n_neighbors + 1, n1)
        _, nbrs = cKDTree(X).query(X[sample], k=k)
        nbrs = nbrs[:, 1:]  # drop the vertex itself
        u, v = tangent_frames(src_normals[sample])
        dx = X[nbrs] - X[sample, None, :]
        a = np.stack([np.einsum("skc,sc->sk", dx, u), np.einsum("skc,sc->sk", dx, v)], axis=2)  # (s, K, 2)
        parts = (sample, nbrs, a, src_areas[sample])
        for array in parts:
            array.flags.writeable = False
        if not seeded:
            return parts
        source.store.put(key, parts)
    return source.store[key]


def orientation_score(source: Mesh, target: Mesh, mapping: np.ndarray, *, n_neighbors: int = 16,
                      n_sample: int = 2000, random_state: int | None = 0) -> float:
    """Fraction of the source on which a vertex map keeps the orientation.

    Parameters
    ----------
    source, target : Mesh
        Orientation is repaired internally (:func:`mesh_orientation`).
    mapping : (n1,) int
        ``mapping[i]`` is the target vertex of source vertex i.
    n_neighbors : int
        Size of the neighbourhood whose image is tested (>= 2).
    n_sample : int
        Source vertices tested (a seeded sample; all if fewer).
    random_state : int or None
        Seed of the sample.

    Returns
    -------
    score : float in [0, 1]
        Area-weighted fraction of tested vertices whose mapped neighbourhood
        keeps its orientation (module docstring); 0.5 when every tested
        neighbourhood collapses onto a single target vertex.
    """
    n_neighbors, n_sample, mapping = _checked(source, target, mapping, n_neighbors, n_sample)
    _, triple, areas = _orientation_signs(source, target, mapping, n_neighbors, n_sample, random_state)
    return _score(triple, areas)


def _checked(source: Mesh, target: Mesh, mapping, n_neighbors, n_sample) -> tuple[int, int, np.ndarray]:
    """The checked ``n_neighbors``, ``n_sample`` and map of :func:`orientation_score`."""
    n_neighbors = check_int("n_neighbors", n_neighbors, minimum=2)
    n_sample = check_int("n_sample", n_sample, minimum=1)
    mapping = np.asarray(mapping)
    if mapping.shape != (source.n_vertices,):
        raise ParameterError(f"The map must have one entry per source vertex ({source.n_vertices}). "
                             f"Got shape {mapping.shape} instead.")
    if mapping.size and (mapping.min() < 0 or mapping.max() >= target.n_vertices):
        raise ParameterError(f"The map must hold target vertex indices in [0, {target.n_vertices}). "
                             f"Got values in [{mapping.min()}, {mapping.max()}] instead.")
    return n_neighbors, n_sample, mapping


def _score(triple: np.ndarray, areas: np.ndarray) -> float:
    """:func:`orientation_score` from the triple products of :func:`_orientation_signs`."""
    w = areas * (triple != 0)
    if w.sum() == 0:
        return 0.5
    return float((w * (triple > 0)).sum() / w.sum())


def _orientation_signs(source: Mesh, target: Mesh, mapping: np.ndarray, n_neighbors: int, n_sample: int,
                       random_state) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Sampled source vertices ``(s,)``, the triple product of each one's mapped frame ``(s,)``
    (positive where the map keeps the orientation) and their areas ``(s,)``."""
    Y = target.vertices
    sample, nbrs, a, areas = _neighbourhoods(source, n_neighbors, n_sample, random_state)
    tgt_normals, _ = oriented_normals(target)
    dy = Y[mapping[nbrs]] - Y[mapping[sample], None, :]  # (s, K, 3)
    c = np.einsum("skc,skt->sct", dy, a)  # (s, 3, 2): images of u, v up to a positive factor
    triple = np.einsum("sc,sc->s", tgt_normals[mapping[sample]], np.cross(c[:, :, 0], c[:, :, 1]))
    return sample, triple, areas


def regional_orientation(source: Mesh, target: Mesh, mapping: np.ndarray, *, n_regions: int = 12,
                         n_neighbors: int = 16, n_sample: int = 2000, random_state: int | None = 0
                         ) -> np.ndarray:
    """The orientation score of a map region by region: a partly mirrored map shows up.

    A map whose legs are swapped left for right while the upper body is
    right keeps the orientation on most of the surface, so its
    :func:`orientation_score` stays high; on the swapped part it reverses
    the orientation. The sampled vertices of :func:`orientation_score` are
    split into ``n_regions`` regions (nearest of as many farthest-point
    seeds, in space), and each region is scored alone.

    Parameters
    ----------
    source, target : Mesh
    mapping : (n1,) int
    n_regions : int
    n_neighbors, n_sample, random_state
        As :func:`orientation_score`.

    Returns
    -------
    scores : (r,) float in [0, 1]
        Area-weighted fraction of each region's sampled vertices whose
        orientation is kept (0.5 where every neighbourhood collapses), in
        order of the seeds.
    """
    n_regions = check_int("n_regions", n_regions, minimum=1)
    _, triple, areas = _orientation_signs(source, target, np.asarray(mapping), n_neighbors, n_sample, random_state)
    return _regional_scores(source, triple, areas, n_regions, n_neighbors, n_sample, random_state)


def orientation_scores(source: Mesh, target: Mesh, mapping: np.ndarray, *, n_regions: int = 12,
                       n_neighbors: int = 16, n_sample: int = 2000, random_state: int | None = 0
                       ) -> tuple[float, np.ndarray]:
    """:func:`orientation_score` and :func:`regional_orientation` of one map, its frames mapped once.

    Parameters
    ----------
    source, target : Mesh
    mapping : (n1,) int
    n_regions, n_neighbors, n_sample, random_state
        As :func:`regional_orientation`.

    Returns
    -------
    score : float
        ``orientation_score(source, target, mapping, ...)``, the same value.
    regional : (r,) float
        ``regional_orientation(source, target, mapping, ...)``, the same values.
    """
    _, triple, areas, regional = _signs_by_region(source, target, mapping, n_regions, n_neighbors, n_sample,
                                                  random_state)
    return _score(triple, areas), regional


def _signs_by_region(source: Mesh, target: Mesh, mapping, n_regions, n_neighbors, n_sample, random_state
                     ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The checked inputs' :func:`_orientation_signs` ``(sample, triple, areas)`` and regional scores ``(r,)``."""
    n_neighbors, n_sample, mapping = _checked(source, target, mapping, n_neighbors, n_sample)
    n_regions = check_int("n_regions", n_regions, minimum=1)
    sample, triple, areas = _orientation_signs(source, target, mapping, n_neighbors, n_sample, random_state)
    return sample, triple, areas, _regional_scores(source, triple, areas, n_regions, n_neighbors, n_sample,
                                                   random_state)


def consistent_vertices(source: Mesh, target: Mesh, mapping: np.ndarray, *, n_regions: int = 12,
                        n_neighbors: int = 16, n_sample: int = 2000, random_state: int | None = 0) -> np.ndarray:
    """The sampled source vertices where a map keeps the orientation, in regions that keep it.

    Parameters
    ----------
    source, target : Mesh
    mapping : (n1,) int
    n_regions, n_neighbors, n_sample, random_state
        As :func:`regional_orientation`.

    Returns
    -------
    vertices : (m,) int
        The sampled vertices of :func:`orientation_score` whose own mapped
        neighbourhood keeps the orientation (triple product > 0) and whose
        region's score (:func:`regional_orientation`) is at least 0.5: the
        part of a partly mirrored map that is not mirrored
        (:mod:`meshcorr.choice.repair`).
    """
    sample, triple, _, regional = _signs_by_region(source, target, mapping, n_regions, n_neighbors, n_sample,
                                                   random_state)
    region, _ = _regions(source, n_regions, n_neighbors, n_sample, random_state)
    return sample[(triple > 0) & (regional[region] >= 0.5)]


def _regions(source: Mesh, n_regions: int, n_neighbors: int, n_sample: int, random_state) -> tuple[np.ndarray, int]:
    """The region of each sampled vertex of :func:`_neighbourhoods` ``(s,)`` and the region count.

    Depends on the source only: cached on it for a seeded sample, like :func:`_neighbourhoods`.
    """
    seeded = isinstance(random_state, (int, np.integer))
    key = ("orientation_regions", n_regions, n_neighbors, n_sample, int(random_state) if seeded else None)
    if seeded and key in source.store:
        return source.store[key]
    sample = _neighbourhoods(source, n_neighbors, n_sample, random_state)[0]
    points = source.vertices[sample]
    seeds = farthest_point_sampling(lambda i: np.linalg.norm(points - points[i], axis=1), len(points),
                                    min(n_regions, len(points)), start=0).indices
    region = cKDTree(points[seeds]).query(points)[1]
    region.flags.writeable = False
    parts = (region, int(len(seeds)))
    if seeded:
        source.store.put(key, parts)
    return parts


def _regional_scores(source: Mesh, triple: np.ndarray, areas: np.ndarray, n_regions: int, n_neighbors: int,
                     n_sample: int, random_state) -> np.ndarray:
    """:func:`regional_orientation` from the triple products of :func:`_orientation_signs`."""
    region, n_seeds = _regions(source, n_regions, n_neighbors, n_sample, random_state)
    w = areas * (triple != 0)
    kept = np.bincount(region, weights=w * (triple > 0), minlength=n_seeds)
    total = np.bincount(region, weights=w, minlength=n_seeds)
    return np.where(total > 0, kept / np.maximum(total, 1e-300), 0.5)
