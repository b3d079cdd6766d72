"""meshcorr.spectral.nystrom: with every vertex a landmark the Nyström extension is the exact eigendecomposition."""

import numpy as np
import pytest
from scipy.spatial.distance import cdist

from meshcorr.errors import ParameterError
from meshcorr.spectral.nystrom import nystrom_eigenpairs


def affinity(distances, sigma):
    return np.exp(-distances ** 2 / (2 * sigma ** 2))


@pytest.fixture(scope="module")
def points():
    return np.random.default_rng(0).uniform(size=(80, 3))


def test_all_landmarks_exact(points):
    D = cdist(points, points)
    sigma = 0.3
    values, vectors = nystrom_eigenpairs(np.arange(len(points)), D, sigma, 5, rcond=1e-12)
    exact_values, exact_vectors = np.linalg.eigh(affinity(D, sigma))
    np.testing.assert_allclose(values, exact_values[::-1][:5], rtol=1e-9)
    overlap = np.abs(np.sum(vectors * exact_vectors[:, ::-1][:, :5], axis=0))
    np.testing.assert_allclose(overlap, 1.0, atol=1e-8)
    np.testing.assert_allclose(vectors.T @ vectors, np.eye(5), atol=1e-10)


def test_landmarks_approximate_the_top_eigenpairs(points):
    D = cdist(points, points)
    sigma = float(D.max())
    landmarks = np.arange(0, 80, 4)
    values, vectors = nystrom_eigenpairs(landmarks, D[landmarks], sigma, 3)
    exact = np.linalg.eigvalsh(affinity(D, sigma))[::-1][:3]
    assert np.all(np.diff(values) <= 0)
    np.testing.assert_allclose(values[0], exact[0], rtol=1e-3)  # the smooth leading pair is captured
    exact_first = np.linalg.eigh(affinity(D, sigma))[1][:, -1]
    assert abs(vectors[:, 0] @ exact_first) > 0.999


def test_refusals(points):
    D = cdist(points, points)[:4]
    with pytest.raises(ParameterError, match="The Gaussian width sigma must be a positive number"):
        nystrom_eigenpairs(np.arange(4), D, 0.0, 2)
    with pytest.raises(ParameterError, match="'k' parameter must be an int <= 4"):
        nystrom_eigenpairs(np.arange(4), D, 1.0, 5)
    same = np.zeros((3, 80))  # three landmarks on one point: rank 1
    with pytest.raises(ParameterError, match="numerical rank 1 < k=2"):
        nystrom_eigenpairs(np.zeros(3, dtype=int), same, 1.0, 2)
