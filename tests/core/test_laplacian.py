"""meshcorr.core.laplacian: the cotangent Laplacian and lumped areas, checked against exact answers."""

import numpy as np
import pytest
import scipy.sparse.linalg as spla

from meshcorr.core.laplacian import laplacian, vertex_areas
from meshcorr.core.mesh import Mesh

from .meshes import grid, sphere


def test_structure_symmetric_constants_in_kernel_positive_semidefinite():
    vertices, faces = sphere(2)
    L, mass = laplacian(Mesh(vertices, faces))
    assert L.shape == (len(vertices), len(vertices)) and L.format == "csc"
    assert abs(L - L.T).max() < 1e-12
    np.testing.assert_allclose(L @ np.ones(len(vertices)), 0.0, atol=1e-10)
    smallest = spla.eigsh(L, k=2, sigma=-1e-3, which="LM", return_eigenvectors=False)
    assert smallest.min() > -1e-8


def test_linear_functions_are_harmonic_inside_a_flat_grid():
    vertices, faces = grid(n=8)
    L, mass = laplacian(Mesh(vertices, faces))
    inside = np.flatnonzero((vertices[:, :2] > 0).all(axis=1) & (vertices[:, :2] < 1).all(axis=1))
    for function in (vertices[:, 0], vertices[:, 1], 2 * vertices[:, 0] - vertices[:, 1] + 3):
        np.testing.assert_allclose((L @ function)[inside], 0.0, atol=1e-12)
    assert mass.sum() == pytest.approx(1.0)
    # Lumped barycentric mass: an inside vertex has six triangles of area h^2 / 2, a third each.
    assert mass[inside] == pytest.approx(np.full(len(inside), (1 / 8) ** 2))


def test_unit_sphere_coordinates_are_eigenfunctions_of_eigenvalue_two():
    vertices, faces = sphere(4)
    mesh = Mesh(vertices, faces)
    L, mass = laplacian(mesh)
    assert mass.sum() == pytest.approx(4 * np.pi, rel=0.01)
    # -Laplace(x) = 2 x on the unit sphere: the Rayleigh quotients x^T L x / x^T M x are 2, and
    # M^-1 L x = 2 x pointwise except at the icosahedron's 12 vertices of valence 5.
    for x in vertices.T:
        assert (x @ (L @ x)) / (x @ (mass * x)) == pytest.approx(2.0, rel=0.005)
    error = np.abs((L @ vertices) / mass[:, None] - 2 * vertices).max(axis=1)
    assert np.sum(error > 0.03) <= 12


def test_cached_and_read_only():
    vertices, faces = sphere(1)
    mesh = Mesh(vertices, faces)
    assert laplacian(mesh) is laplacian(mesh)
    assert vertex_areas(mesh) is laplacian(mesh)[1]
    assert not vertex_areas(mesh).flags.writeable
    assert vertex_areas(mesh).sum() == pytest.approx(mesh.area)
