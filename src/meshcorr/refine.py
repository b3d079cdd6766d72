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
``potpourri3d``, by shift-invert Lanczos (``scipy.sparse.linalg.eigsh``), and
is cached on the :class:`~meshcorr.mesh.Mesh` per size.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.optimize import linear_sum_assignment
from scipy.sparse.linalg import eigsh

from ._params import check_int
from .embedding import deterministic_start, sign_convention
from .errors import ParameterError
from .mesh import Mesh


def laplace_basis(mesh: Mesh, k: int, *, random_state: int | None = 0) -> tuple[np.ndarray, np.ndarray]:
    """First ``k`` Laplace-Beltrami eigenpairs, cached on the mesh.

    Parameters
    ----------
    mesh : Mesh
    k : int
        Number of eigenpairs (<= n_vertices - 1).
    random_state : int or None
        Seed of the Lanczos start vector.

    Returns
    -------
    eigenvalues : (k,) float
        Ascending, the first ~0.
    basis : (n, k) float, read-only
        Eigenvectors orthonormal for the mass matrix scaled to unit total
        area (:math:`\\Phi^T M \\Phi = I`, :math:`\\sum M = 1`), signs fixed
        by :func:`meshcorr.embedding.sign_convention`.
    """
    import potpourri3d as pp3d

    n = mesh.n_vertices
    k = check_int("refine_k", k, minimum=2, maximum=max(2, n - 1))
    key = ("laplace_basis", k, random_state)
    if key not in mesh._cache:
        V, F = np.asarray(mesh.vertices), np.asarray(mesh.faces)
        L = pp3d.cotan_laplacian(V, F)
        # Unit total area: bases of meshes of different sizes are then comparable
        # (an orthogonal functional map cannot absorb a scale factor).
        mass = pp3d.vertex_areas(V, F)
        mass = mass / mass.sum()
        # A tiny negative shift keeps the shift-inverted operator non-singular
        # (L is singular: constants are in its kernel).
        shift = -1e-8 * float(np.abs(L.diagonal()).mean() / mass.mean())
        values, vectors = eigsh(L.tocsc(), k=k, M=sp.diags(mass).tocsc(), sigma=shift, which="LM",
                                v0=deterministic_start(n, random_state))
        order = np.argsort(values)
        values, vectors = values[order], sign_convention(vectors[:, order])
        vectors.flags.writeable = False
        mesh._cache[key] = (values, vectors)
    return mesh._cache[key]


def _nearest_rows(queries: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Index of the nearest row of ``points`` for each row of ``queries``.

    Brute force in row blocks (BLAS), faster than a KD-tree in the 20-60
    dimensions of a spectral basis.
    """
    sq = np.einsum("ij,ij->i", points, points)
    out = np.empty(len(queries), dtype=np.int64)
    step = max(1, 4_000_000 // max(1, len(points)))
    for start in range(0, len(queries), step):
        block = queries[start:start + step]
        out[start:start + step] = np.argmin(sq[None, :] - 2.0 * block @ points.T, axis=1)
    return out


def zoomout(source_basis: np.ndarray, target_basis: np.ndarray, mapping: np.ndarray, *,
            k_start: int = 16, step: int = 2, n_sample: int = 500, bijective: bool = False,
            random_state: int | None = 0) -> tuple[np.ndarray, list[dict]]:
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
        ZoomOut); the last step maps every source vertex to every target
        vertex.
    bijective : bool
        Make the final map one-to-one by linear assignment in the spectral
        space (needs ``n1 == n2``).
    random_state : int or None
        Seed of the samples.

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
        # The orthogonal C closest to the least-squares fit of A C = B (Procrustes).
        U, _, Vt = np.linalg.svd(A.T @ B)
        C = U @ Vt
        new = s2[_nearest_rows(A @ C, target_basis[s2, :k])]
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
    return _nearest_rows(queries, target_basis), history


def refine_map(source: Mesh, target: Mesh, mapping: np.ndarray, *, k: int = 40, k_start: int = 16,
               step: int = 2, n_sample: int = 500, bijective: bool = False,
               random_state: int | None = 0) -> tuple[np.ndarray, list[dict]]:
    """ZoomOut refinement of a vertex map between two meshes.

    Parameters
    ----------
    source, target : Mesh
    mapping : (n1,) int
        ``mapping[i]`` is the target vertex of source vertex i.
    k : int
        Final Laplace-Beltrami basis size (clipped to the vertex counts).
    k_start, step, n_sample, bijective, random_state
        See :func:`zoomout`.

    Returns
    -------
    mapping : (n1,) int
    history : list of dict
    """
    k = check_int("refine_k", k, minimum=2)
    k = min(k, source.n_vertices - 1, target.n_vertices - 1)
    mapping = np.asarray(mapping)
    if mapping.shape != (source.n_vertices,) or (mapping.size and (
            mapping.min() < 0 or mapping.max() >= target.n_vertices)):
        raise ParameterError(f"The map to refine must hold one target vertex in [0, {target.n_vertices}) "
                             f"per source vertex ({source.n_vertices}). Got shape {mapping.shape}.")
    _, phi1 = laplace_basis(source, k, random_state=random_state)
    _, phi2 = laplace_basis(target, k, random_state=random_state)
    return zoomout(phi1, phi2, mapping, k_start=min(k_start, k), step=step, n_sample=n_sample,
                   bijective=bijective, random_state=random_state)
