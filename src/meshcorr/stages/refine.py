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
:class:`~meshcorr.core.mesh.Mesh` per size.

Speed at 100k+ vertices (issue 5). The last step maps every source vertex
to its nearest target vertex in the K-dimensional spectral space; brute
force costs ``O(n1 n2 K)`` (~40 s at 115k vertices). Above
:data:`PRUNE_ABOVE` target vertices it is pruned exactly by the triangle
inequality over seeded cells (:func:`_nearest_rows_pruned`, in the spirit of
cluster-pruning exact search, e.g. Fukunaga & Narendra, "A branch and bound
algorithm for computing k-nearest neighbors", IEEE Trans. Computers 1975):
the same map, ~15x less work on spectral coordinates. A KD-tree is slower
than brute force in 40 dimensions, and a greedy descent over the target's
one-ring from a coarse winner stops in local minima for about half the
vertices (both measured, ``benchmarks/RESULTS-refine.md``). Every
brute-force search of more than :data:`SCREEN_ABOVE` pairs is first done in
single precision with a rigorous error bound, and only its near-ties again
in double precision (:func:`_nearest_rows`): the double-precision map, ~25 %
less time at 5k x 5k x 40 (``benchmarks/RESULTS-collections.md``). ARPACK runs
with single-threaded BLAS: its work outside the sparse solves is
memory-bound, and threads only add waits on a shared 2-core machine.
The bases depend on the meshes only: :func:`meshcorr.pipeline.run.match`
computes them in a worker thread while its other stages run
(:func:`prefetch_bases`).
"""

from __future__ import annotations

import threading
import time
from contextlib import contextmanager

import numpy as np
import scipy.sparse as sp
from scipy.optimize import linear_sum_assignment
from scipy.sparse.linalg import LinearOperator, eigsh, splu

from ..runtime.interrupt import deferred_interrupt
from ..runtime.checks import check_int
from ..runtime.threads import parallel_map, single_blas_thread, wait_for
from ..spectral.embedding import deterministic_start, sign_convention
from ..errors import ParameterError
from ..core.laplacian import laplacian
from ..core.mesh import Mesh

#: Target vertex count above which the final all-vertices search prunes by
#: cells (:func:`_nearest_rows_pruned`, exact) instead of brute force.
PRUNE_ABOVE = 20_000
#: Sampled pairs each known landmark pair counts as in every ZoomOut fit (see :func:`zoomout`).
LANDMARK_WEIGHT = 20


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
        by :func:`meshcorr.spectral.embedding.sign_convention`.
    """
    return _laplace_basis(mesh, k, random_state, cancel=None)


class _Cancelled(Exception):
    """Raised inside the eigensolver of an abandoned :class:`BasisPrefetch`."""


def _laplace_basis(mesh: Mesh, k: int, random_state: int | None,
                   cancel: threading.Event | None) -> tuple[np.ndarray, np.ndarray]:
    """:func:`laplace_basis`; raises :class:`_Cancelled` between two solves once ``cancel`` is set."""
    n = mesh.n_vertices
    k = check_int("refine_k", k, minimum=2, maximum=max(2, n - 1))
    key = ("laplace_basis", k, random_state)
    if key not in mesh.store:
        L, mass = laplacian(mesh)  # cotangent Laplacian, or a point cloud's (meshcorr.core.laplacian)
        # Unit total area: bases of meshes of different sizes are then comparable
        # (an orthogonal functional map cannot absorb a scale factor).
        mass = mass / mass.sum()
        M = sp.diags(mass).tocsc()
        # A tiny negative shift keeps the shift-inverted operator non-singular
        # (L is singular: constants are in its kernel).
        shift = -1e-8 * float(np.abs(L.diagonal()).mean() / mass.mean())
        # The shift-inverted operator eigsh would build itself (scipy's SpLuInv of
        # L - shift M), written out so that an abandoned prefetch can stop it.
        lu = splu((L - shift * M).tocsc())

        def solve(x: np.ndarray) -> np.ndarray:
            if cancel is not None and cancel.is_set():
                raise _Cancelled
            return lu.solve(np.asarray(x).astype(float))

        # ARPACK's reorthogonalisation is memory-bound BLAS-2: threads only add
        # waits (measured 2x slower with 2 threads on a loaded 2-core machine).
        with single_blas_thread():
            values, vectors = eigsh(L, k=k, M=M, sigma=shift, which="LM", v0=deterministic_start(n, random_state),
                                    OPinv=LinearOperator(L.shape, matvec=solve, dtype=float))
        order = np.argsort(values)
        values, vectors = values[order], sign_convention(vectors[:, order])
        vectors.flags.writeable = False
        mesh.store.put(key, (values, vectors))
    return mesh.store[key]


#: Squared distances per block of :func:`_nearest_rows` (8 MB of float64).
_NEAREST_BLOCK = 1 << 20
#: Single-precision squared distances per block of the screen of :func:`_nearest_rows` (2 MB: blocks of
#: 2^18-2^21 entries took 0.066, 0.056, 0.060 and 0.076 s at 5k x 5k x 40 on one core).
_SCREEN_BLOCK = 1 << 19
#: Fewest ``len(queries) * len(points)`` for which :func:`_nearest_rows` screens in single precision
#: first (below it the screen's second pass costs more than it saves).
SCREEN_ABOVE = 1 << 20
#: Unit roundoff of float32 and float64.
_U32, _U64 = 2.0 ** -24, 2.0 ** -53


def _nearest_rows(queries: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Index of the nearest row of ``points`` for each row of ``queries``: the double-precision answer.

    Brute force in row blocks (BLAS), faster than a KD-tree in the 20-60
    dimensions of a spectral basis (``benchmarks/RESULTS-refine.md``). The
    answer is that of the double-precision search
    (:func:`_nearest_rows_double`), whose near-ties do not depend on the
    number of BLAS threads; single precision alone is 2x faster but was
    measured to resolve a near-tie differently with 1 and 2 threads. Above
    :data:`SCREEN_ABOVE` pairs the squared distances are first computed in
    single precision, with a rigorous bound on their error
    (:func:`_single_precision_bound`): a query whose best point beats the
    runner-up by more than twice the bound (plus the double-precision
    search's own bound) has that best point as its double-precision answer,
    provably; every other query (a near-tie, a few percent of them) is
    searched again in double precision. Same map as the double-precision
    search, with any number of threads.
    """
    queries, points = np.asarray(queries, dtype=np.float64), np.asarray(points, dtype=np.float64)
    if len(queries) * len(points) <= SCREEN_ABOVE or not (np.isfinite(queries).all() and np.isfinite(points).all()):
        return _nearest_rows_double(queries, points)
    augmented_points = _augmented_points(points)
    augmented_queries = np.hstack([queries, np.ones((len(queries), 1))])
    bound = _single_precision_bound(augmented_queries, augmented_points)
    points32 = augmented_points.astype(np.float32)
    queries32 = augmented_queries.astype(np.float32)
    out = np.empty(len(queries), dtype=np.int64)
    unsure = np.zeros(len(queries), dtype=bool)
    step = max(1, min(len(queries), _SCREEN_BLOCK // max(1, len(points))))
    buffer = np.empty((step, len(points)), dtype=np.float32)
    for start in range(0, len(queries), step):
        block = np.matmul(queries32[start:start + step], points32, out=buffer[:min(step, len(queries) - start)])
        rows = np.arange(len(block))
        best = np.argmin(block, axis=1)
        best_value = block[rows, best].astype(np.float64)
        block[rows, best] = np.inf
        runner_up = block.min(axis=1).astype(np.float64)
        out[start:start + len(block)] = best
        unsure[start:start + len(block)] = runner_up - best_value <= 2.0 * bound[start:start + len(block)]
    if unsure.any():
        out[unsure] = _nearest_rows_double(queries[unsure], points)
    return out


def _augmented_points(points: np.ndarray) -> np.ndarray:
    """``(K + 1, n)``: the columns ``[-2 p, |p|^2]``, so that ``[q, 1] . column = |q - p|^2 - |q|^2``."""
    return np.vstack([-2.0 * points.T, np.einsum("ij,ij->i", points, points)[None, :]])


def _single_precision_bound(augmented_queries: np.ndarray, augmented_points: np.ndarray) -> np.ndarray:
    r"""``(n1,)``: a bound on the error of each single-precision ``[q, 1] . [-2 p, |p|^2]``, plus the double one.

    Rounding the inputs to float32 changes each product term by at most
    :math:`(2u + u^2)|a_k b_k|`, and a dot product of :math:`n` terms in
    floating point (any summation order, FMA or not) is within
    :math:`\gamma_n \sum_k |a_k b_k|`, :math:`\gamma_n = nu / (1 - nu)`, of
    the exact one (Higham, "Accuracy and stability of numerical algorithms",
    2nd ed., section 3.1). Here :math:`\sum_k |a_k b_k| = 2 \sum_k |q_k||p_k|
    + |p|^2 \le 2 |q| P + P^2` (Cauchy-Schwarz), :math:`P` the largest point
    norm. The double-precision search's own :math:`\gamma_n` (with
    :math:`u = 2^{-53}`) is added, so that a screened answer is the one it
    would give; the whole is doubled for the rounding of this bound itself.
    """
    n = augmented_points.shape[0]
    gamma32, gamma64 = (n * u / (1.0 - n * u) for u in (_U32, _U64))
    largest = float(np.sqrt(augmented_points[-1].max()))  # the last row holds |p|^2
    norms = np.sqrt(np.einsum("ij,ij->i", augmented_queries[:, :-1], augmented_queries[:, :-1]))
    return 2.0 * (gamma32 + 2.0 * _U32 + _U32 ** 2 + gamma64) * (2.0 * norms * largest + largest ** 2)


def _nearest_rows_double(queries: np.ndarray, points: np.ndarray) -> np.ndarray:
    """:func:`_nearest_rows` in double precision only (the reference answer)."""
    queries, points = np.asarray(queries, dtype=np.float64), np.asarray(points, dtype=np.float64)
    # |q - p|^2 - |q|^2 = [q, 1] . [-2 p, |p|^2]: one product per block, no separate pass adding |p|^2
    # (25 % faster at 5k x 5k x 40).
    augmented_points = _augmented_points(points)
    augmented_queries = np.hstack([queries, np.ones((len(queries), 1))])
    out = np.empty(len(queries), dtype=np.int64)
    step = max(1, min(len(queries), _NEAREST_BLOCK // max(1, len(points))))
    # One buffer for every block: fresh 30 MB temporaries per block cost as
    # much in page faults as the products themselves (measured at 5k).
    buffer = np.empty((step, len(points)))
    for start in range(0, len(queries), step):
        block = augmented_queries[start:start + step]
        out[start:start + step] = np.argmin(np.matmul(block, augmented_points, out=buffer[:len(block)]), axis=1)
    return out


def _nearest_rows_pruned(queries: np.ndarray, points: np.ndarray, *, n_cells: int = 2000,
                         random_state: int | None = 0) -> np.ndarray:
    """Exact nearest row of ``points`` for each query, by cells and the triangle inequality.

    ``n_cells`` seeded points are cell centres :math:`c`; every point joins
    the cell of its nearest centre, and :math:`r_c` is the cell's radius.
    Queries are grouped by their nearest centre. A query :math:`q` whose
    best distance so far is :math:`d` cannot have its nearest point in cell
    :math:`c` when :math:`\\lVert q - c \\rVert - r_c > d`; each group first
    searches its own cell, then brute-forces only the cells that bound
    leaves open. The answer equals brute force (up to ties) at a fraction of
    its ``O(n1 n2 K)`` cost when points lie on a low-dimensional manifold,
    as spectral coordinates of a surface do.
    """
    n2 = len(points)
    n_cells = min(n_cells, n2)
    rng = np.random.default_rng(random_state)
    chosen = np.sort(rng.choice(n2, size=n_cells, replace=False))
    centres = points[chosen]
    owner = _nearest_rows(points, centres)
    owner[chosen] = np.arange(n_cells)  # no cell is empty, even with duplicate points
    radius = np.zeros(n_cells)
    np.maximum.at(radius, owner, np.linalg.norm(points - centres[owner], axis=1))
    order = np.argsort(owner, kind="stable")
    bounds = np.searchsorted(owner[order], np.arange(n_cells + 1))
    group = _nearest_rows(queries, centres)
    q_order = np.argsort(group, kind="stable")
    q_bounds = np.searchsorted(group[q_order], np.arange(n_cells + 1))
    sq_c = np.einsum("ij,ij->i", centres, centres)
    sq_p = np.einsum("ij,ij->i", points, points)
    out = np.empty(len(queries), dtype=np.int64)
    for c in np.flatnonzero(np.diff(q_bounds)):
        rows = q_order[q_bounds[c]:q_bounds[c + 1]]
        q = queries[rows]
        sq_q = np.einsum("ij,ij->i", q, q)
        own = order[bounds[c]:bounds[c + 1]]  # never empty: the centre itself is in it
        best = np.sqrt(np.maximum((sq_p[own][None, :] - 2.0 * q @ points[own].T).min(axis=1) + sq_q, 0.0))
        to_centres = np.sqrt(np.maximum(sq_c[None, :] - 2.0 * q @ centres.T + sq_q[:, None], 0.0))
        open_cells = np.flatnonzero((to_centres - radius[None, :] <= best[:, None] * (1 + 1e-9)).any(axis=0))
        cand = np.concatenate([order[bounds[o]:bounds[o + 1]] for o in open_cells])
        out[rows] = cand[np.argmin(sq_p[cand][None, :] - 2.0 * q @ points[cand].T, axis=1)]
    return out


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
        new = s2[_nearest_rows(A[:len(s1)] @ C, target_basis[s2, :k])]
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


def orthogonal_fit(A: np.ndarray, B: np.ndarray) -> np.ndarray:
    """The orthogonal ``(k, k)`` matrix C closest to the least-squares fit of ``A C = B`` (Procrustes).

    Parameters
    ----------
    A, B : (m, k) float
    """
    U, _, Vt = np.linalg.svd(A.T @ B)
    return U @ Vt


def nearest_vertices(queries: np.ndarray, points: np.ndarray, *, random_state: int | None = 0) -> np.ndarray:
    """Exact nearest row of ``points`` ``(n2, d)`` for each of ``queries`` ``(n1, d)``.

    Brute force (:func:`_nearest_rows`), pruned by cells above :data:`PRUNE_ABOVE` points
    (:func:`_nearest_rows_pruned`, seeded by ``random_state``; the same answer up to ties).
    """
    if len(points) > PRUNE_ABOVE:
        return _nearest_rows_pruned(queries, points, random_state=random_state)
    return _nearest_rows(queries, points)


def check_vertex_map(mapping, source: Mesh, target: Mesh) -> np.ndarray:
    """``mapping`` as an array, checked to hold one target vertex per source vertex (ParameterError)."""
    mapping = np.asarray(mapping)
    if mapping.shape != (source.n_vertices,) or (mapping.size and (
            mapping.min() < 0 or mapping.max() >= target.n_vertices)):
        raise ParameterError(f"The map to refine must hold one target vertex in [0, {target.n_vertices}) "
                             f"per source vertex ({source.n_vertices}). Got shape {mapping.shape}.")
    return mapping


def pair_bases(source: Mesh, target: Mesh, k: int, *, random_state: int | None = 0
               ) -> tuple[np.ndarray, np.ndarray]:
    """Both meshes' first ``k`` Laplace-Beltrami eigenvectors (:func:`laplace_basis`), one thread each.

    The two eigenproblems are independent and SuperLU's solves release the GIL: two threads
    take ~1.5x less wall time on 2 cores (same results). parallel_map holds the process-wide
    BLAS limit in this thread around both, so that neither thread's limiter can restore the
    other's (meshcorr.runtime.threads).
    """
    phi1, phi2 = parallel_map(lambda mesh: laplace_basis(mesh, k, random_state=random_state)[1],
                              (source, target))
    return phi1, phi2


def _basis_size(k: int, source: Mesh, target: Mesh) -> int:
    """The basis size both meshes use: ``k`` clipped to the vertex counts."""
    k = check_int("refine_k", k, minimum=2)
    return min(k, source.n_vertices - 1, target.n_vertices - 1)


class BasisPrefetch:
    """Laplace-Beltrami bases being computed in a worker thread (see :func:`prefetch_bases`).

    Attributes
    ----------
    seconds : float or None
        Wall time the worker took, once it has finished.
    """

    def __init__(self, source: Mesh, target: Mesh, k: int, random_state: int | None, *,
                 start: bool = True) -> None:
        self.seconds: float | None = None
        self._error: BaseException | None = None
        self._cancel = threading.Event()
        # Waiters wait on this event, not on Thread.join: a join interrupted by Ctrl-C can mark a
        # running thread as stopped on Python 3.11 (its tstate lock is released by the interrupted
        # waiter), and the interpreter then finalises under the running worker and crashes.
        self._done = threading.Event()
        if start:
            threading.Thread(target=self._compute, args=(source, target, k, random_state),
                             name="meshcorr-bases").start()
        else:
            self._done.set()

    def _compute(self, source: Mesh, target: Mesh, k: int, random_state: int | None) -> None:
        start = time.perf_counter()
        try:
            for mesh in (source, target):
                if not self._cancel.is_set():
                    _laplace_basis(mesh, k, random_state, self._cancel)
        except _Cancelled:
            pass
        except BaseException as error:  # re-raised in the caller's thread by wait()
            self._error = error
        finally:
            self.seconds = time.perf_counter() - start
            self._done.set()

    def wait(self) -> None:
        """Block until both bases are cached on their meshes; re-raise the worker's error."""
        self._done.wait()
        if self._error is not None:
            raise self._error

    def cancel(self) -> None:
        """Stop the worker at its next sparse solve (or between the meshes) and wait for it."""
        self._cancel.set()
        wait_for(self._done)  # through Ctrl-C too: the interpreter must not exit under the worker


@contextmanager
def prefetch_bases(source: Mesh, target: Mesh, k: int, *, random_state: int | None = 0,
                   enabled: bool = True):
    """Compute the refinement's two Laplace-Beltrami bases in a worker thread.

    The bases depend on the meshes only, not on the map, so
    :func:`meshcorr.pipeline.run.match` starts them as soon as the meshes are
    loaded: the worker spends most of its time in SuperLU solves and ARPACK,
    which release the GIL, and runs on the second core while the pipeline's
    other stages run on the first (the bases are the same arrays
    :func:`laplace_basis` would compute, so the map is the same). Inside the
    block BLAS is limited to one thread process-wide (held by the calling
    thread: see :mod:`meshcorr.runtime.threads`), so the two threads do not
    oversubscribe the cores; leaving the block waits for the worker and
    restores it. After an error inside the block (or Ctrl-C) the worker is
    cancelled: it stops at its next sparse solve (milliseconds; a sparse
    factorisation under way, up to ~1 s at 100k vertices, runs to its end).

    Parameters
    ----------
    source, target : Mesh
    k : int
        Basis size (clipped as :func:`refine_map` clips it).
    random_state : int or None
        Seed of the Lanczos start vectors.
    enabled : bool
        False: no thread, the block runs as it is.

    Yields
    ------
    prefetch : BasisPrefetch
        ``prefetch.wait()`` blocks until the bases are cached.
    """
    if not enabled:
        yield BasisPrefetch(source, target, 0, random_state, start=False)
        return
    k = _basis_size(k, source, target)
    with single_blas_thread():
        prefetch = None
        try:
            with deferred_interrupt():  # a Ctrl-C as the worker starts finds it to cancel
                prefetch = BasisPrefetch(source, target, k, random_state)
            yield prefetch
        except BaseException:
            if prefetch is not None:
                prefetch.cancel()
            raise
        prefetch.wait()


def refine_map(source: Mesh, target: Mesh, mapping: np.ndarray, *, k: int = 40, k_start: int = 16,
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
    k = _basis_size(k, source, target)
    mapping = check_vertex_map(mapping, source, target)
    phi1, phi2 = pair_bases(source, target, k, random_state=random_state)
    return zoomout(phi1, phi2, mapping, k_start=min(k_start, k), step=step, n_sample=n_sample,
                   bijective=bijective, random_state=random_state, landmarks=landmarks)
