"""meshcorr.stages.landmarks: a dense map from landmark pairs by geodesic descriptors."""

import numpy as np
import pytest

from meshcorr.errors import ParameterError
from meshcorr.stages.landmarks import landmark_descriptors, landmark_disagreement, landmark_map, landmark_table

N = 21


def path_row(i):
    """Distances along a path of N vertices with unit edges."""
    return np.abs(np.arange(N) - i).astype(float)


def test_descriptors_are_distances_over_their_mean():
    descriptors = landmark_descriptors(path_row, np.array([0, 20]))
    raw = np.column_stack([path_row(0), path_row(20)])
    np.testing.assert_allclose(descriptors, raw / raw.mean())
    np.testing.assert_allclose(descriptors.mean(), 1.0)


def test_the_identity_from_its_own_landmarks():
    mapping = landmark_map(path_row, path_row, np.array([[0, 0], [20, 20]]))
    np.testing.assert_array_equal(mapping, np.arange(N))


def test_a_reversed_copy_is_found_and_scale_does_not_matter():
    def scaled(i):  # the same path three times longer; the pairs say its numbering runs the other way
        return 3.0 * path_row(i)

    pairs = np.array([[0, 20], [20, 0]])
    mapping = landmark_map(path_row, scaled, pairs)
    np.testing.assert_array_equal(mapping, np.arange(N)[::-1])


def test_landmarks_are_mapped_exactly_even_against_their_descriptors():
    pairs = np.array([[0, 0], [20, 20], [10, 3]])  # the third pair disagrees with the other two
    mapping = landmark_map(path_row, path_row, pairs)
    assert mapping[10] == 3 and mapping[0] == 0 and mapping[20] == 20


def test_booleans_are_no_landmark_indices():
    # numpy took [(True, 3)] for vertex 1 -> vertex 3 (issue 31, item 19).
    for landmarks in ([(True, 3)], [(2, np.False_)], [[0, 1], [False, 2]]):
        with pytest.raises(ParameterError, match="not True or False"):
            landmark_table(landmarks)
    assert landmark_table([(1, 3)]).tolist() == [[1, 3]]
    assert landmark_table(np.array([[1, 3]])).tolist() == [[1, 3]]


def test_the_disagreement_names_the_pair_whose_distances_do_not_fit():
    # On a path and a copy twice as long, every right pair keeps its distances (after scaling);
    # a pair sent elsewhere disagrees with all the others (issue 31, item 9).
    def scaled(i):
        return 2.0 * path_row(i)

    pairs = np.array([[0, 0], [4, 4], [8, 8], [12, 12], [16, 16], [20, 20]])
    np.testing.assert_allclose(landmark_disagreement(path_row, scaled, pairs), 0.0, atol=1e-12)
    pairs[2, 1] = 19
    disagreement = landmark_disagreement(path_row, scaled, pairs)
    assert int(np.argmax(disagreement)) == 2
    assert disagreement[2] > 3 * np.median(disagreement) and disagreement[2] > 0.3


def test_two_pairs_always_agree():
    assert landmark_disagreement(path_row, path_row, np.array([[0, 20], [5, 6]])).tolist() == [0.0, 0.0]
