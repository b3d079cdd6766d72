"""Refinement of a dense vertex map by spectral upsampling (ZoomOut).

The map from TPS-ICP and proximity matching is accurate only at the scale of
a (k-1)-dimensional embedding, k = 6. ZoomOut (Melzi, Ren, Rodola, Sharma,
Wonka, Ovsjanikov, "ZoomOut: spectral upsampling for efficient shape
correspondence", ACM TOG 38(6), SIGGRAPH Asia 2019) refines it in the
Laplace-Beltrami eigenbases :math:`\\Phi_1, \\Phi_2` of the two meshes by
alternating, for growing basis sizes :math:`k = k_0, k_0 + s, ..., K`:

.. math::

    C_k = \\arg\\min_C \\lVert \\Phi_1^{(k)}[S] \\, C - \\Phi_2^{(k)}[T(S)] \\rVert_F,
    \\qquad
    T(i) = \\arg\\min_j \\lVert \\Phi_1^{(k)}[i] \\, C_k - \\Phi_2^{(k)}[j] \\rVert

where :math:`T` is the source-to-target vertex map, :math:`C_k` the
``k x k`` functional map pulling target functions back to the source and
:math:`S` a seeded sample of source vertices (the least-squares form on a
sample is the sub-sampled ZoomOut of Magnet & Ovsjanikov, "Fast Sinkhorn
filters", CVPR 2021, section 5; with all vertices it equals the mass-weighted
projection up to the mass weights). Each step is a linear fit followed by a
nearest-neighbour query, so the map stays close to its start: ZoomOut refines
but does not change the orientation of a map (a mirrored start stays
mirrored, a correct one stays correct).

The basis solves :math:`L \\phi = \\lambda M \\phi` with the cotangent Laplacian
:math:`L` and the lumped (barycentric) mass matrix :math:`M` of
``potpourri3d`` (of a point cloud: its Laplacian and mass from
:mod:`meshcorr.core.laplacian`), by shift-invert Lanczos
(``scipy.sparse.linalg.eigsh``), and is cached on the
:class:`~meshcorr.core.mesh.Mesh` per size (:mod:`meshcorr.spectral.basis`).

Speed at 100k+ vertices (issue 5). The last step maps every source vertex
to its nearest target vertex in the K-dimensional spectral space; brute
force costs ``O(n1 n2 K)`` (~40 s at 115k vertices). Above
:data:`PRUNE_ABOVE` target vertices it is pruned exactly by the triangle
inequality over seeded cells (:mod:`meshcorr.spectral.nearest`, in the spirit of
cluster-pruning exact search, e.g. Fukunaga & Narendra, "A branch and bound
algorithm for computing k-nearest neighbors", IEEE Trans. Computers 1975):
the same map, ~15x less work on spectral coordinates. A KD-tree is slower
than brute force in 40 dimensions, and a greedy descent over the target's
one-ring from a coarse winner stops in local minima for about half the
vertices (both measured, ``benchmarks/RESULTS-refine.md``). Every
brute-force search of more than :data:`meshcorr.spectral.nearest.SCREEN_ABOVE` pairs is first done in
single precision with a rigorous error bound, and only its near-ties again
in double precision (:func:`meshcorr.spectral.nearest.nearest_rows`): the double-precision map, ~25 %
less time at 5k x 5k x 40 (``benchmarks/RESULTS-collections.md``). ARPACK runs
with single-threaded BLAS: its work outside the sparse solves is
memory-bound, and threads only add waits on a shared 2-core machine.
The bases depend on the meshes only: :func:`meshcorr.pipeline.run.match`
computes them in a worker thread while its other stages run
(:func:`meshcorr.spectral.basis.prefetch_bases`).
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import linear_sum_assignment

from ..runtime.checks import MapMessages, check_int, check_vertex_map
from ..errors import ParameterError
from ..core.mesh import Mesh
from ..spectral.basis import basis_size, orthogonal_fit, pair_bases
from ..spectral.nearest import nearest_rows, nearest_vertices

__all__ = ["LANDMARK_WEIGHT", "REFINE_K", "REFINED_MAP", "refine_map", "zoomout"]

#: The Laplace-Beltrami basis size the refinements end with (the default of :class:`meshcorr.Settings`).
REFINE_K = 40
#: Sampled pairs each known landmark pair counts as in every ZoomOut fit (see :func:`zoomout`).
LANDMARK_WEIGHT = 20
#: The words of a map refused by the refinement (:func:`meshcorr.runtime.checks.check_vertex_map`): whole
#: numbers in ``[0, n_target)``, not necessarily of an integer dtype, no -1.
REFINED_MAP = MapMessages(
    not_integer=None,
    wrong_length="The map to refine must hold one target vertex in [0, {n_target}) per source vertex ({n_source}). "
                 "Got shape {shape}.",
    out_of_range="The map to refine must hold one target vertex in [0, {n_target}) per source vertex ({n_source}). "
                 "Got shape {shape}.",
    unmapped=False)


def zoomout(source_basis: np.ndarray, target_basis: np.ndarray, mapping: np.ndarray, *,
            k_start: int = 16, step: int = 2, n_sample: int = 500, bijective: bool = False,
            random_state: int | None = 0, landmarks: np.ndarray | None = None
            ) -> tuple[np.ndarray, list[dict]]:
    """Refine a vertex map by spectral upsampling (module docstring).

    Parameters
    ----------
    source_basis : (n1, K) float
        Laplace-Beltrami eigenvectors of the source, ascending eigenvalues.
    target_basis : (n2, K) float
        Those of the target; ``K`` is the final basis size.
    mapping : (n1,) int
        Initial map: ``mapping[i]`` is the target vertex of source vertex i.
    k_start : int
        First basis size (small enough for the initial map to be right at
        that scale).
    step : int
        Basis functions added per iteration.
    n_sample : int
        Vertices sampled on each mesh for the iterations (sub-sampled
        ZoomOut); the last step maps every source vertex to its nearest
        target vertex (exact; pruned above :data:`PRUNE_ABOVE` target
        vertices).
    bijective : bool
        Make the final map one-to-one by linear assignment in the spectral
        space (needs ``n1 == n2``).
    random_state : int or None
        Seed of the samples.
    landmarks : (L, 2) int, optional
        Known (source vertex, target vertex) pairs: each is added to every
        fit as :data:`LANDMARK_WEIGHT` sampled pairs, so the functional map
        keeps them (a soft constraint; the caller pins them in the final map).

    Returns
    -------
    mapping : (n1,) int
        The refined map.
    history : list of dict
        Per iteration: basis size ``k`` and the fraction of the sampled
        source vertices whose image changed.
    """
    K = source_basis.shape[1]
    if target_basis.shape[1] != K:
        raise ParameterError(f"The two bases must have the same size. Got {K} and {target_basis.shape[1]}.")
    k_start = check_int("refine_k_start", k_start, minimum=1, maximum=K)
    step = check_int("refine_step", step, minimum=1)
    n_sample = check_int("refine_n_sample", n_sample, minimum=1)
    n1, n2 = len(source_basis), len(target_basis)
    if bijective and n1 != n2:
        raise ParameterError(f"A bijective refined map needs equal vertex counts; got {n1} and {n2}.")
    rng = np.random.default_rng(random_state)

    def draw(n):
        return np.arange(n) if n <= n_sample else np.sort(rng.choice(n, size=n_sample, replace=False))

    s1, s2 = draw(n1), draw(n2)
    images = np.asarray(mapping, dtype=np.int64)[s1]  # target vertex of each sampled source vertex
    history: list[dict] = []
    C = None
    for k in list(range(k_start, K, step)) + [K]:
        A, B = source_basis[s1, :k], target_basis[images, :k]
        if landmarks is not None:  # known pairs weigh in every fit as LANDMARK_WEIGHT sampled pairs each
            A = np.vstack([A, np.repeat(source_basis[landmarks[:, 0], :k], LANDMARK_WEIGHT, axis=0)])
            B = np.vstack([B, np.repeat(target_basis[landmarks[:, 1], :k], LANDMARK_WEIGHT, axis=0)])
        C = orthogonal_fit(A, B)
        new = s2[nearest_rows(A[:len(s1)] @ C, target_basis[s2, :k])]
        history.append({"k": int(k), "changed": float(np.mean(new != images))})
        images = new
    queries = source_basis @ C
    if bijective:
        B = target_basis
        cost = (np.einsum("ij,ij->i", queries, queries)[:, None] - 2.0 * queries @ B.T
                + np.einsum("ij,ij->i", B, B)[None, :])
        rows, cols = linear_sum_assignment(cost)
        out = np.empty(n1, dtype=np.int64)
        out[rows] = cols
        return out, history
    return nearest_vertices(queries, target_basis, random_state=random_state), history




def refine_map(source: Mesh, target: Mesh, mapping: np.ndarray, *, k: int = REFINE_K, k_start: int = 16,
               step: int = 2, n_sample: int = 500, bijective: bool = False,
               random_state: int | None = 0, landmarks: np.ndarray | None = None
               ) -> tuple[np.ndarray, list[dict]]:
    """ZoomOut refinement of a vertex map between two meshes.

    Parameters
    ----------
    source, target : Mesh
    mapping : (n1,) int
        ``mapping[i]`` is the target vertex of source vertex i.
    k : int
        Final Laplace-Beltrami basis size (clipped to the vertex counts).
    k_start, step, n_sample, bijective, random_state, landmarks
        See :func:`zoomout`.

    Returns
    -------
    mapping : (n1,) int
    history : list of dict
    """
    k = basis_size(k, source, target)
    mapping = check_vertex_map(mapping, source.n_vertices, target.n_vertices, messages=REFINED_MAP)
    phi1, phi2 = pair_bases(source, target, k, random_state=random_state)
    return zoomout(phi1, phi2, mapping, k_start=min(k_start, k), step=step, n_sample=n_sample,
                   bijective=bijective, random_state=random_state, landmarks=landmarks)
