"""The lift of the copies' map to every vertex (meshcorr.stages.lift): extended bases, local search, exact cases."""

import numpy as np
import pytest
import trimesh
from scipy.linalg import subspace_angles

from meshcorr import datasets as ds
from meshcorr.core.coarse import CoarseCopy
from meshcorr.core.laplacian import laplacian
from meshcorr.core.mesh import as_mesh
from meshcorr.errors import ParameterError
from meshcorr.spectral.basis import laplace_basis
from meshcorr.stages.lift import extended_basis, interpolation_matrix, lift_to_fine, local_nearest


@pytest.fixture(scope="module")
def coarse_and_fine():
    """A 2000-vertex creature and its midpoint subdivision (7994 vertices, the original ones first)."""
    shape = ds.creature(resolution=3)
    coarse = as_mesh((shape.vertices, shape.faces), name="coarse")
    vertices, faces = trimesh.remesh.subdivide(shape.vertices, shape.faces)
    return coarse, as_mesh((vertices, faces), name="fine")


def test_interpolation_weights_are_barycentric_and_exact_on_the_coarse_surface(coarse_and_fine):
    coarse, fine = coarse_and_fine
    P = interpolation_matrix(fine.vertices, coarse)
    assert P.shape == (fine.n_vertices, coarse.n_vertices)
    assert np.diff(P.indptr).max() <= 3 and P.data.min() >= 0
    np.testing.assert_allclose(np.asarray(P.sum(axis=1)).ravel(), 1.0, atol=1e-12)
    # midpoint subdivision keeps every fine vertex on the coarse surface: linear interpolation is exact there
    np.testing.assert_allclose(P @ coarse.vertices, fine.vertices, atol=1e-9)
    # the original vertices (numbered first) interpolate to themselves
    np.testing.assert_allclose((P @ np.eye(coarse.n_vertices)[:, :5])[:5], np.eye(5), atol=1e-9)


def test_extended_basis_spans_the_direct_basis_of_the_fine_mesh(coarse_and_fine):
    coarse, fine = coarse_and_fine
    k = 8
    extended = extended_basis(interpolation_matrix(fine.vertices, coarse), laplace_basis(coarse, k)[1])
    direct = laplace_basis(fine, k)[1]
    mass = laplacian(fine)[1]
    root = np.sqrt(mass / mass.sum())[:, None]
    # the same subspace up to signs and rotations within near-equal eigenvalues: small principal angles
    # (measured 0.0024 rad for the first six functions, 0.0033 for eight)
    assert np.max(subspace_angles(root * extended[:, :6], root * direct[:, :6])) < 0.02
    assert np.max(subspace_angles(root * extended, root * direct)) < 0.02
    # and nearly orthonormal for the fine mesh's mass (the lift does not need it exactly)
    gram = extended.T @ ((mass / mass.sum())[:, None] * extended)
    np.testing.assert_allclose(gram, np.eye(k), atol=0.01)  # measured 0.004


def _reindexed(fine, rng):
    """The fine mesh with its vertices renumbered: ``(mesh, order)``, new vertex i = old vertex order[i]."""
    order = rng.permutation(fine.n_vertices)
    inverse = np.empty_like(order)
    inverse[order] = np.arange(len(order))
    return as_mesh((fine.vertices[order], inverse[fine.faces]), name="renumbered"), order


def test_lift_against_a_reindexed_copy_is_the_permutation(coarse_and_fine):
    coarse, fine = coarse_and_fine
    renumbered, order = _reindexed(fine, np.random.default_rng(3))
    source = CoarseCopy(coarse, np.arange(coarse.n_vertices), np.zeros(fine.n_vertices, dtype=np.int64), fine)
    # the target's copy: the same coarse mesh, its parents the renumbered original vertices
    inverse = np.argsort(order)
    target = CoarseCopy(coarse, inverse[np.arange(coarse.n_vertices)], np.zeros(fine.n_vertices, dtype=np.int64),
                        renumbered)
    mapping = lift_to_fine((source, target), np.arange(coarse.n_vertices), k=20, iterations=1, n_sample=2000)
    np.testing.assert_array_equal(mapping, inverse)  # fine vertex v is renumbered vertex inverse[v]
    landmarks = np.array([[0, inverse[1]], [5, inverse[7]]])  # pinned pairs are held as given
    pinned = lift_to_fine((source, target), np.arange(coarse.n_vertices), k=20, iterations=0, landmarks=landmarks)
    np.testing.assert_array_equal(pinned[landmarks[:, 0]], landmarks[:, 1])
    np.testing.assert_array_equal(np.delete(pinned, landmarks[:, 0]), np.delete(inverse, landmarks[:, 0]))


def test_local_search_with_every_candidate_is_the_exact_nearest_neighbour():
    rng = np.random.default_rng(0)
    points, queries = rng.normal(size=(300, 10)), rng.normal(size=(200, 10))
    exact = np.argmin(((queries[:, None] - points[None]) ** 2).sum(axis=2), axis=1)
    np.testing.assert_array_equal(local_nearest(queries, points, n_candidates=300, search_dims=6, eps=0.0), exact)
    np.testing.assert_array_equal(local_nearest(queries, points, n_candidates=1, search_dims=10, eps=0.0), exact)


def test_lift_refuses_a_coarse_map_of_the_wrong_length_and_no_candidates(coarse_and_fine):
    coarse, fine = coarse_and_fine
    copy = CoarseCopy(coarse, np.arange(coarse.n_vertices), np.zeros(fine.n_vertices, dtype=np.int64), fine)
    with pytest.raises(ParameterError):
        lift_to_fine((copy, copy), np.arange(coarse.n_vertices - 1))
    with pytest.raises(ParameterError, match="n_candidates"):
        lift_to_fine((copy, copy), np.arange(coarse.n_vertices), n_candidates=0)
    with pytest.raises(ParameterError, match="iterations"):
        lift_to_fine((copy, copy), np.arange(coarse.n_vertices), iterations=-1)
