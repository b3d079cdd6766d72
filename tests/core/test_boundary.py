"""meshcorr.core.boundary: boundary half-edges, loops and their lengths, distance to the boundary."""

import numpy as np
import pytest

from meshcorr.core.boundary import boundary_distance, boundary_edges, enclosed_areas, mesh_boundary
from meshcorr.core.mesh import Mesh

from .meshes import grid, sphere


def test_two_triangles_boundary_in_their_winding():
    faces = np.array([[0, 1, 2], [0, 2, 3]])
    edges = boundary_edges(faces, 4)
    assert sorted(map(tuple, edges.tolist())) == [(0, 1), (1, 2), (2, 3), (3, 0)]


def test_closed_mesh_has_no_boundary():
    vertices, faces = sphere(1)
    assert boundary_edges(faces, len(vertices)).shape == (0, 2)
    boundary = mesh_boundary(Mesh(vertices, faces))
    assert boundary.n_loops == 0 and boundary.longest == 0.0 and boundary.total == 0.0
    assert np.all(np.isinf(boundary_distance(Mesh(vertices, faces))))


def test_square_with_a_hole_two_loops_longest_first():
    vertices, faces = grid(n=6, size=1.0, holes={(2, 2), (2, 3), (3, 2), (3, 3)})
    boundary = mesh_boundary(Mesh(vertices, faces))
    assert boundary.n_loops == 2
    np.testing.assert_allclose(boundary.lengths, [4.0, 4 * 2 / 6], rtol=1e-12)
    area = 1.0 - 4 / 36
    assert boundary.area == pytest.approx(area)
    assert boundary.longest == pytest.approx(4.0 / np.sqrt(area))
    assert boundary.total == pytest.approx((4.0 + 4 / 3) / np.sqrt(area))
    assert len(boundary.vertices) == 24 + 8
    # Each edge's loop: the outer square's edges lie on x or y in {0, 1}.
    outer = boundary.edges[boundary.loop == 0]
    on_side = np.isin(vertices[outer][:, :, :2], [0.0, 1.0]).any(axis=2).all(axis=1)
    assert on_side.all() and len(outer) == 24



def test_enclosed_areas_of_a_square_with_a_hole():
    vertices, faces = grid(n=6, size=1.0, holes={(2, 2), (2, 3), (3, 2), (3, 3)})
    area = 1.0 - 4 / 36
    np.testing.assert_allclose(enclosed_areas(Mesh(vertices, faces)), [1.0 / area, (2 / 6) ** 2 / area], rtol=1e-12)
    assert len(enclosed_areas(Mesh(*sphere(1)))) == 0

def test_distance_to_the_boundary_of_a_square():
    vertices, faces = grid(n=10, size=1.0)
    distance = boundary_distance(Mesh(vertices, faces))
    exact = np.minimum.reduce([vertices[:, 0], 1 - vertices[:, 0], vertices[:, 1], 1 - vertices[:, 1]])
    assert np.all(distance[exact == 0] == 0.0)
    # The heat method on a 1/10 spacing: within 0.1 everywhere, 0.03 on average; farthest at the centre.
    np.testing.assert_allclose(distance, exact, atol=0.1)
    assert np.abs(distance - exact).mean() < 0.03
    assert np.allclose(vertices[np.argmax(distance), :2], 0.5)
    assert not distance.flags.writeable
