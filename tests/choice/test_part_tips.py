"""meshcorr.choice.part_tips: a part's tips assigned to the whole's, a tip made by the cut left out."""

import numpy as np
import pytest

from meshcorr.choice.extremities import Extremities
from meshcorr.choice.part_tips import match_part_tips


def tips(points):
    points = np.asarray(points, dtype=float)
    distances = np.linalg.norm(points[:, None] - points[None], axis=2)
    return Extremities(np.arange(len(points)), distances)


def test_the_tips_in_common_are_assigned_at_any_scale_and_a_tip_of_the_cut_falls_out():
    whole = np.array([[0.0, 0.0], [3.0, 0.5], [1.0, 4.0], [4.0, 3.5], [-2.0, 2.5]])
    part = np.vstack([0.5 * whole[:4], [[9.0, -7.0]]])  # four tips of the whole at half size, one new
    assignments = match_part_tips(tips(part), tips(whole))
    energy, pairs = assignments[0]
    np.testing.assert_array_equal(pairs, [[0, 0], [1, 1], [2, 2], [3, 3]])
    assert energy == pytest.approx(0.0, abs=1e-12)
    assert all(len(other) <= 4 for _, other in assignments)


def test_fewer_than_three_tips_give_no_assignment():
    assert match_part_tips(tips([[0.0, 0.0], [1.0, 0.0]]), tips([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])) == []
