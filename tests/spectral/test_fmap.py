"""meshcorr.spectral.fmap: orthonormal Laplace-Beltrami bases, the functional map of a vertex map and back."""

import numpy as np
import pytest

import meshcorr.datasets as datasets
from meshcorr.core.mesh import as_mesh
from meshcorr.errors import ParameterError
from meshcorr.spectral.fmap import functional_map, laplace_beltrami, point_map


@pytest.fixture(scope="module")
def tube():
    shape = datasets.tube(n_along=20, n_around=12)
    return as_mesh((shape.vertices, shape.faces), name="tube")


def test_basis_orthonormal_for_the_unit_area_mass(tube):
    values, basis, mass = laplace_beltrami(tube, 8)
    assert basis.shape == (tube.n_vertices, 8)
    assert mass.sum() == pytest.approx(1.0)
    np.testing.assert_allclose(basis.T @ (mass[:, None] * basis), np.eye(8), atol=1e-8)
    assert np.all(np.diff(values) >= -1e-12) and abs(values[0]) < 1e-8 and values[1] > 1e-3
    np.testing.assert_allclose(np.abs(basis[:, 0]), 1.0, rtol=1e-6)  # constant, unit norm on unit area


def test_identity_map_gives_the_identity_matrix(tube):
    fmap = functional_map(tube, tube, np.arange(tube.n_vertices), k=6)
    np.testing.assert_allclose(fmap.C, np.eye(6), atol=1e-8)
    assert fmap.source_basis.shape == fmap.target_basis.shape == (tube.n_vertices, 6)
    partial = functional_map(tube, tube, np.arange(tube.n_vertices), k=4, k_target=6)
    assert partial.C.shape == (4, 6)


def test_unmapped_rows_are_left_out(tube):
    mapping = np.arange(tube.n_vertices)
    mapping[::2] = -1
    fmap = functional_map(tube, tube, mapping, k=4)
    _, basis, mass = laplace_beltrami(tube, 4)
    kept = mapping >= 0
    np.testing.assert_allclose(fmap.C, basis[kept].T @ (mass[kept, None] * basis[kept]), atol=1e-12)


def test_point_map_inverts_an_orthogonal_functional_map():
    rng = np.random.default_rng(3)
    target = rng.normal(size=(60, 5))
    C, _ = np.linalg.qr(rng.normal(size=(5, 5)))
    order = rng.permutation(60)[:40]
    source = target[order] @ C.T  # so that source @ C = target[order]
    np.testing.assert_array_equal(point_map(C, source, target), order)


def test_point_map_refusals():
    with pytest.raises(ParameterError, match=r"C has shape \(3, 3\) but the bases have 4 and 4 columns"):
        point_map(np.eye(3), np.zeros((5, 4)), np.zeros((5, 4)))
    with pytest.raises(ParameterError, match="C holds NaN or infinite values"):
        point_map(np.full((2, 2), np.nan), np.zeros((5, 2)), np.zeros((5, 2)))
