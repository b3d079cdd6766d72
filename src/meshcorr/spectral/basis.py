"""Laplace-Beltrami bases of meshes and point clouds, and the fits written in them.

The shared spectral kernels of ZoomOut (:mod:`meshcorr.stages.refine`),
functional maps (:mod:`meshcorr.spectral.fmap`), smooth shells
(:mod:`meshcorr.stages.shells`), the oriented start, the map repair and
partial shapes. The basis solves :math:`L \\phi = \\lambda M \\phi` with the
cotangent Laplacian :math:`L` and the lumped (barycentric) mass matrix
:math:`M` of ``potpourri3d`` (of a point cloud: its Laplacian and mass from
:mod:`meshcorr.core.laplacian`), by shift-invert Lanczos
(``scipy.sparse.linalg.eigsh``), and is kept in the mesh's per-shape store
(:attr:`meshcorr.core.mesh.Mesh.store`) per size. ARPACK runs with
single-threaded BLAS: its work outside the sparse solves is memory-bound, and
threads only add waits on a shared 2-core machine.

The bases depend on the meshes only: :func:`meshcorr.pipeline.run.match`
computes them in a worker thread while its other stages run
(:func:`prefetch_bases`). Two bases are compared through an orthogonal
functional map :math:`C = \\arg\\min_{C^T C = I} \\lVert A C - B \\rVert_F`
(:func:`orthogonal_fit`).
"""

from __future__ import annotations

import threading
import time
from contextlib import contextmanager

import numpy as np
import scipy.sparse as sp
from scipy.sparse.linalg import LinearOperator, eigsh, splu

from ..runtime.interrupt import deferred_interrupt
from ..runtime.checks import check_int
from ..runtime.threads import parallel_map, single_blas_thread, wait_for
from .embedding import deterministic_start, sign_convention
from ..core.laplacian import laplacian
from ..core.mesh import Mesh

__all__ = ["BasisPrefetch", "basis_size", "laplace_basis", "orthogonal_fit", "pair_bases", "prefetch_bases"]


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


def orthogonal_fit(A: np.ndarray, B: np.ndarray) -> np.ndarray:
    """The orthogonal ``(k, k)`` matrix C closest to the least-squares fit of ``A C = B`` (Procrustes).

    Parameters
    ----------
    A, B : (m, k) float
    """
    U, _, Vt = np.linalg.svd(A.T @ B)
    return U @ Vt



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


def basis_size(k: int, source: Mesh, target: Mesh) -> int:
    """The basis size both meshes use: ``k`` clipped to the vertex counts, ``min(k, n1 - 1, n2 - 1)``."""
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
        Basis size (clipped as :func:`basis_size` clips it).
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
    k = basis_size(k, source, target)
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
