"""meshcorr.core.mesh: a Mesh is read-only, knows its area and refuses what later steps cannot use."""

import numpy as np
import pytest

from meshcorr.core.mesh import Mesh, as_mesh
from meshcorr.errors import MeshError

from .meshes import grid, sphere


def test_arrays_read_only_and_counts():
    vertices, faces = grid(n=4, size=2.0)
    mesh = as_mesh((vertices, faces), name="square")
    assert mesh.n_vertices == 25 and len(mesh.faces) == 32 and not mesh.is_cloud
    assert mesh.name == "square" and mesh.n_input == 25 and mesh.n_caps == 0
    np.testing.assert_array_equal(mesh.kept, np.arange(25))
    for array in (mesh.vertices, mesh.faces, mesh.kept):
        with pytest.raises(ValueError):
            array[0] = 0
    assert mesh.area == pytest.approx(4.0)
    assert repr(mesh) == "Mesh(name='square', n_vertices=25, n_faces=32)"


def test_sphere_area_and_a_copy_of_the_input():
    vertices, faces = sphere(3)
    mesh = Mesh(vertices, faces)
    vertices[0] = 100.0  # the mesh keeps its own copy
    assert mesh.area == pytest.approx(4 * np.pi, rel=0.01)
    assert np.linalg.norm(mesh.vertices[0]) == pytest.approx(1.0)


def test_a_point_cloud_is_a_mesh_without_faces():
    vertices, _ = sphere(2)
    cloud = as_mesh(vertices, name="cloud")
    assert cloud.is_cloud and cloud.faces.shape == (0, 3)
    assert "point cloud" in repr(cloud)
    assert cloud.area == pytest.approx(4 * np.pi, rel=0.05)


@pytest.mark.parametrize("faces, message", [
    (np.array([[0, 1, 5]]), "a face names vertex 5, outside 0..3"),
    (np.array([[0.0, 1.0, 2.0]]), "faces must be integer vertex indices"),
    (np.array([[0, 1]]), r"vertices must be \(n, 3\) and faces \(m, 3\)"),
])
def test_refusals(faces, message):
    vertices = np.eye(4, 3)
    with pytest.raises(MeshError, match=message):
        Mesh(vertices, faces, name="bad")


def test_non_finite_vertices_refused():
    vertices = np.eye(3)
    vertices[1, 2] = np.nan
    with pytest.raises(MeshError, match="NaN or infinite vertex coordinates"):
        Mesh(vertices, np.array([[0, 1, 2]]))
