"""Small hand-made meshes shared by the tests of meshcorr.core (exact areas, boundaries and Laplacians)."""

import numpy as np
import trimesh


def grid(n: int = 6, size: float = 1.0, holes=()):
    """A flat ``size x size`` square in the z = 0 plane: ``(n + 1)^2`` vertices, two triangles per cell.

    ``holes`` lists cells ``(i, j)`` left out. Returns ``(vertices, faces)``, counter-clockwise seen from +z.
    """
    xs = np.linspace(0.0, size, n + 1)
    x, y = np.meshgrid(xs, xs, indexing="ij")
    vertices = np.column_stack([x.ravel(), y.ravel(), np.zeros(x.size)])
    faces = []
    for i in range(n):
        for j in range(n):
            if (i, j) in holes:
                continue
            a, b, c, d = i * (n + 1) + j, (i + 1) * (n + 1) + j, (i + 1) * (n + 1) + j + 1, i * (n + 1) + j + 1
            faces += [(a, b, c), (a, c, d)]
    return vertices, np.array(faces, dtype=np.int64)


def sphere(subdivisions: int = 3):
    """A unit icosphere ``(vertices, faces)``, outward winding."""
    mesh = trimesh.creation.icosphere(subdivisions=subdivisions)
    return np.asarray(mesh.vertices), np.asarray(mesh.faces, dtype=np.int64)
