"""An icosphere, for checking geodesic solvers against the great-circle formula (:func:`sphere`)."""

from __future__ import annotations

import numpy as np

from .shape import int_parameter, positive_parameter

__all__ = ["sphere"]

def sphere(*, subdivisions: int = 4, radius: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """An icosphere, for checking geodesic distances against great circles.

    Parameters
    ----------
    subdivisions : int, default 4
        Loop subdivisions of an icosahedron, 0 to 7: ``10 * 4**k + 2``
        vertices (642 at 3, 2562 at 4, 10242 at 5).
    radius : float, default 1.0
        Radius (> 0); every vertex lies on the sphere.

    Returns
    -------
    vertices : (n, 3) float64
    faces : (m, 3) int64
        Oriented outwards. The geodesic distance between vertices ``i`` and
        ``j`` is ``radius * arccos(<v_i, v_j> / radius**2)``.
    """
    import trimesh

    subdivisions = int_parameter(subdivisions, "subdivisions", "sphere", 0, 7)
    radius = positive_parameter(radius, "radius", "sphere")
    mesh = trimesh.creation.icosphere(subdivisions=subdivisions, radius=radius)
    vertices = np.asarray(mesh.vertices, dtype=np.float64)
    # project exactly onto the sphere
    vertices = radius * vertices / np.linalg.norm(vertices, axis=1, keepdims=True)
    return vertices, np.asarray(mesh.faces, dtype=np.int64)
