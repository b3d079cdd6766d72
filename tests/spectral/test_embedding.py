"""Gaussian affinity and spectral embedding: against dense eigh, up to sign."""

import numpy as np
import pytest

from meshcorr.datasets import tube
from meshcorr.spectral.embedding import gaussian_affinity, sign_convention, spectral_embedding, top_eigenpairs
from meshcorr.errors import ParameterError
from meshcorr.core.geodesics import pairwise_geodesics


@pytest.fixture(scope="module")
def affinity():
    # The bumps break the capsule's symmetry, so the top eigenvalues are simple.
    mesh = tube(n_along=24, n_around=12)
    D = pairwise_geodesics(mesh.vertices, mesh.faces, "heat")
    return D, gaussian_affinity(D)


def test_affinity_formula(affinity):
    D, A = affinity
    sigma = D.max()
    np.testing.assert_allclose(A, np.exp(-D**2 / (2 * sigma**2)), rtol=1e-12)
    np.testing.assert_array_equal(np.diag(A), 1.0)
    # With sigma = max distance every affinity is at least exp(-1/2).
    assert A.min() >= np.exp(-0.5) - 1e-12


def test_affinity_rejects_bad_sigma():
    with pytest.raises(ParameterError, match="sigma must be a positive number"):
        gaussian_affinity(np.zeros((3, 3)))


def test_eigsh_agrees_with_dense_eigh_up_to_sign(affinity):
    _, A = affinity
    values, vectors = top_eigenpairs(A, 6)
    ref_values, ref_vectors = np.linalg.eigh(A)
    ref_values, ref_vectors = ref_values[::-1][:6], ref_vectors[:, ::-1][:, :6]
    np.testing.assert_allclose(values, ref_values, rtol=1e-9)
    assert np.min(np.diff(-values)) > 1e-6 * values[0]  # simple eigenvalues
    signs = np.sign(np.sum(vectors * ref_vectors, axis=0))
    np.testing.assert_allclose(vectors, ref_vectors * signs, atol=1e-7)


def test_embedding_is_deterministic_and_scaled(affinity):
    _, A = affinity
    values, emb = spectral_embedding(A, 6, scale=True, random_state=3)
    values2, emb2 = spectral_embedding(A, 6, scale=True, random_state=3)
    np.testing.assert_array_equal(emb, emb2)
    _, raw = spectral_embedding(A, 6, scale=False, random_state=3)
    assert emb.shape == (A.shape[0], 5)
    np.testing.assert_allclose(emb, raw * np.sqrt(values[1:]), rtol=1e-12)
    # Unscaled columns are the unit eigenvectors 2..k.
    np.testing.assert_allclose(np.linalg.norm(raw, axis=0), 1.0, rtol=1e-10)


def test_sign_convention_makes_largest_entry_positive():
    rng = np.random.default_rng(0)
    vectors = rng.normal(size=(50, 4))
    fixed = sign_convention(vectors * np.array([1, -1, 1, -1]))
    idx = np.argmax(np.abs(fixed), axis=0)
    assert np.all(fixed[idx, np.arange(4)] > 0)
    np.testing.assert_allclose(np.abs(fixed), np.abs(vectors))


def test_k_must_be_at_least_two(affinity):
    _, A = affinity
    with pytest.raises(ParameterError, match="'k' parameter must be an int >= 2. Got 1"):
        spectral_embedding(A, 1)
