"""The Laplace-Beltrami operator and the vertex areas of a mesh or a point cloud.

One place for both, used by the refinement's bases (:mod:`meshcorr.stages.refine`),
the exported functional maps (:mod:`meshcorr.spectral.fmap`), the curvature
(:mod:`meshcorr.choice.curvature`), coverage (:mod:`meshcorr.evaluation.metrics`), the
baselines' alignment and the surface area of a cloud
(:attr:`meshcorr.core.mesh.Mesh.area`).

Meshes
    The cotangent Laplacian :math:`L` (positive semi-definite) and the
    lumped barycentric mass :math:`M` (a third of the adjacent triangles'
    areas) of potpourri3d.
Point clouds
    The point-cloud Laplacian of Sharp & Crane, "A Laplacian for
    nonmanifold triangle meshes" (SGP 2020), through
    ``robust_laplacian.point_cloud_laplacian``: each point's
    :data:`~meshcorr.core.pointcloud.N_NEIGHBORS` nearest neighbours are
    triangulated locally (a Delaunay triangulation of their projection on
    the tangent plane), the union of these triangles (a "tufted cover") is
    intrinsically mollified against near-degenerate triangles and gives the
    cotangent Laplacian and a lumped mass, the same objects as on a mesh,
    with the same sign convention. The mass sums to the sampled surface's
    area (measured: TOSCA cat0's 5000 vertices as a cloud, +0.3 %).

Both are cached on the :class:`~meshcorr.core.mesh.Mesh` (whose arrays are read-only).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from .pointcloud import N_NEIGHBORS, triangulation_failed

__all__ = ["laplacian", "vertex_areas", "MOLLIFY_FACTOR"]

#: Intrinsic mollification of the cloud Laplacian, relative to the mean edge length (its default).
MOLLIFY_FACTOR = 1e-5


def laplacian(mesh) -> tuple[sp.csc_matrix, np.ndarray]:
    """Laplace-Beltrami operator and lumped vertex areas, cached on the mesh.

    Parameters
    ----------
    mesh : Mesh
        A triangle mesh or a point cloud (``mesh.is_cloud``).

    Returns
    -------
    L : (n, n) sparse float, CSC
        Weak (stiffness) Laplacian, symmetric positive semi-definite, constants in its kernel:
        :math:`L x \\approx -M \\Delta x` for a function :math:`x` on the vertices.
    mass : (n,) float, read-only
        Lumped vertex areas, in the mesh's units squared (not normalised).
    """
    key = ("laplacian",)
    if key not in mesh.store:
        V = np.asarray(mesh.vertices, dtype=np.float64)
        if mesh.is_cloud:
            import robust_laplacian

            try:
                L, M = robust_laplacian.point_cloud_laplacian(V, mollify_factor=MOLLIFY_FACTOR,
                                                              n_neighbors=min(N_NEIGHBORS, len(V) - 1))
            except RuntimeError as error:
                raise triangulation_failed(error, "its Laplacian") from None
            mass = np.asarray(M.diagonal(), dtype=np.float64)
        else:
            import potpourri3d as pp3d

            F = np.asarray(mesh.faces)
            L, mass = pp3d.cotan_laplacian(V, F), pp3d.vertex_areas(V, F)
        mass = np.array(mass, dtype=np.float64)
        mass.flags.writeable = False
        mesh.store.put(key, (sp.csc_matrix(L), mass))
    return mesh.store[key]


def vertex_areas(mesh) -> np.ndarray:
    """Lumped vertex areas ``(n,)`` of a mesh or a point cloud: the mass of :func:`laplacian`."""
    return laplacian(mesh)[1]
