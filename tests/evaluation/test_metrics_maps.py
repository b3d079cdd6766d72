"""evaluate_map on maps that do not fit the target, and the geodesic-row cover of one pair.

Error paths and edge cases the mutation run (benchmarks/RESULTS-tests.md) found untested.
"""

import numpy as np
import pytest

from meshcorr import datasets as ds
from meshcorr.errors import ParameterError
from meshcorr.evaluation.metrics import _greedy_cover, evaluate_map
from meshcorr.evaluation.ground_truth import identity_truth


@pytest.fixture(scope="module")
def sphere():
    return ds.sphere(subdivisions=1)  # 42 vertices


@pytest.mark.parametrize("entry, value", [(3, -2), (5, 42), (0, 1000)])
def test_a_map_entry_outside_the_target_is_refused(sphere, entry, value):
    vertices, faces = sphere
    mapping = np.arange(len(vertices))
    mapping[entry] = value
    truth = identity_truth(len(vertices), len(vertices))
    message = rf"Map entry {entry} is {value}, outside the target's vertices 0\.\.41 \(-1 marks unmapped\)"
    with pytest.raises(ParameterError, match=message):
        evaluate_map((vertices, faces), mapping, truth)


def test_unmapped_entries_are_allowed_and_counted(sphere):
    vertices, faces = sphere
    mapping = np.arange(len(vertices))
    mapping[[2, 7]] = -1
    report = evaluate_map((vertices, faces), mapping, identity_truth(len(vertices), len(vertices)))
    assert report["n_unmapped"] == 2 and report["mean_error"] == 0.0
    assert report["under"]["0.05"] == pytest.approx(40 / 42)  # unmapped points count as misses


def test_the_cover_of_one_pair_is_its_true_vertex():
    np.testing.assert_array_equal(_greedy_cover(np.array([3]), np.array([7])), [7])
    assert _greedy_cover(np.array([], dtype=np.int64), np.array([], dtype=np.int64)).size == 0


def test_a_map_as_close_to_the_mirror_as_to_the_truth_is_not_flipped(sphere):
    vertices, faces = sphere
    truth = identity_truth(len(vertices), len(vertices))
    shifted = np.roll(np.arange(len(vertices)), 1)
    report = evaluate_map((vertices, faces), shifted, truth, sym_truth=truth)
    assert report["sym_mean_error"] == report["mean_error"] > 0 and report["flipped"] is False
