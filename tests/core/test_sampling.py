"""meshcorr.core.sampling: greedy farthest-point sampling with known answers on a path and a grid."""

import numpy as np
import pytest

from meshcorr.core.sampling import farthest_point_sampling
from meshcorr.errors import ParameterError

N = 11


def path_row(i):
    """Distances along a path of N vertices with unit edges."""
    return np.abs(np.arange(N) - i).astype(float)


def test_path_known_landmarks_and_radii():
    landmarks = farthest_point_sampling(path_row, N, 4, start=0)
    np.testing.assert_array_equal(landmarks.indices, [0, 10, 5, 2])
    np.testing.assert_array_equal(landmarks.radii, [10, 5, 2, 2])
    np.testing.assert_array_equal(landmarks.distances, np.stack([path_row(i) for i in (0, 10, 5, 2)]))
    assert landmarks.diameter == 10.0


def test_every_vertex_is_taken_and_the_last_radius_is_zero():
    landmarks = farthest_point_sampling(path_row, N, N, start=3)
    assert sorted(landmarks.indices) == list(range(N))
    assert landmarks.radii[-1] == 0.0
    assert np.all(np.diff(landmarks.radii) <= 0)


def test_covering_radius_holds_on_a_grid():
    points = np.stack(np.meshgrid(np.arange(15.0), np.arange(15.0)), axis=-1).reshape(-1, 2)

    def row(i):
        return np.linalg.norm(points - points[i], axis=1)

    landmarks = farthest_point_sampling(row, len(points), 12, random_state=7)
    assert len(set(landmarks.indices.tolist())) == 12
    nearest = landmarks.distances.min(axis=0)
    assert nearest.max() == pytest.approx(landmarks.radii[-1])
    assert np.all(np.diff(landmarks.radii) <= 1e-12)
    again = farthest_point_sampling(row, len(points), 12, random_state=7)
    np.testing.assert_array_equal(landmarks.indices, again.indices)  # seeded start


def test_a_solver_giving_a_chosen_vertex_a_tiny_distance_does_not_repeat_it():
    def noisy(i):
        row = path_row(i)
        row[i] = 1e-9
        return row

    landmarks = farthest_point_sampling(noisy, N, N, start=0)
    assert len(set(landmarks.indices.tolist())) == N
    assert landmarks.distances[0, 0] == 0.0


def test_refusals():
    with pytest.raises(ParameterError, match="'n_landmarks' parameter must be an int <= 11"):
        farthest_point_sampling(path_row, N, 12)
    with pytest.raises(ParameterError, match="'start' parameter must be an int <= 10"):
        farthest_point_sampling(path_row, N, 2, start=11)
