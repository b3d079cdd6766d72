"""Per-mesh spectral data: what the matching stages need from each mesh.

A :class:`Spectrum` bundles the spectral embedding of a mesh with access to
its (normalised) geodesic distances. The dense builder here computes
all-pairs geodesics and the exact top-k eigenpairs of the full affinity
matrix (docs/method.md, steps 1-3); other builders (e.g. a landmark-based one
for large meshes) only need to return the same object.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from .embedding import gaussian_affinity, spectral_embedding
from ..core.mesh import Mesh
from ..runtime.timing import StageTimer


@dataclass
class Spectrum:
    """Spectral description of one mesh.

    Attributes
    ----------
    eigenvalues : (k,) float
        Top eigenvalues of the affinity matrix, descending.
    embedding : (n, k - 1) float
        Spectral coordinates of the vertices (first eigenvector dropped).
    geodesics_from : callable
        ``geodesics_from(i)`` returns the geodesic distances from vertex i
        to every vertex, ``(n,)``, divided by ``max_geodesic``.
    max_geodesic : float
        The largest geodesic distance on the mesh (the Gaussian width).
    mode : {"dense", "scalable"}
        The builder that made it (:mod:`meshcorr.spectral.modes`).
    rows : dict
        Scalable mode: the unnormalised geodesic rows computed so far
        (vertex -> ``(n,)``), which ``geodesics_from`` serves; empty in the
        dense mode, whose rows are those of ``mesh.geodesic_matrix``.
    memo : dict
        Values derived from this spectrum alone, kept in memory while it lives
        (e.g. :func:`meshcorr.choice.extremities.spectrum_extremities`); not saved
        with a prepared shape, recomputed after loading.
    """

    eigenvalues: np.ndarray
    embedding: np.ndarray
    geodesics_from: Callable[[int], np.ndarray]
    max_geodesic: float
    mode: str = "dense"
    rows: dict = field(default_factory=dict)
    memo: dict = field(default_factory=dict, repr=False, compare=False)


def dense_spectrum(mesh: Mesh, *, k: int, geodesic: str, scale: bool, random_state: int | None,
                   timer: StageTimer) -> Spectrum:
    """Exact spectrum from all-pairs geodesics (``O(n^2)`` memory).

    Parameters
    ----------
    mesh : Mesh
    k : int
        Eigenpairs computed.
    geodesic : str
        Geodesic solver name.
    scale : bool
        Eigenvalue scaling.
    random_state : int or None
    timer : StageTimer
        Receives the "geodesics" and "embedding" stages.
    """
    with timer.stage("geodesics"):
        D = mesh.geodesic_matrix(geodesic, progress=timer.reporter("geodesics"))
    with timer.stage("embedding"):
        sigma = float(D.max())
        values, embedding = spectral_embedding(gaussian_affinity(D, sigma), k, scale=scale,
                                               random_state=random_state)
    return Spectrum(values, embedding, dense_rows(D, sigma), sigma, mode="dense")


def dense_rows(D: np.ndarray, sigma: float) -> Callable[[int], np.ndarray]:
    """``geodesics_from(i)`` of the dense mode: row i of ``D`` ``(n, n)`` divided by ``sigma``."""
    return lambda i: D[i] / sigma
