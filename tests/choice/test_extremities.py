"""meshcorr.choice.extremities: the tips of a tube and a creature, and their assignment onto themselves."""

import numpy as np
import pytest

import meshcorr.datasets as datasets
from meshcorr.choice.extremities import EXTREMITY_RADIUS, find_extremities, match_extremities
from meshcorr.core.mesh import as_mesh


def geodesics(shape):
    mesh = as_mesh((shape.vertices, shape.faces))
    D = mesh.geodesic_matrix("heat")
    return mesh, (lambda i: D[i])


def test_a_tube_has_its_two_ends():
    mesh, rows = geodesics(datasets.tube(n_along=24, n_around=10))
    tips = find_extremities(mesh, rows)
    assert len(tips.vertices) == 2
    x = mesh.vertices[:, 0]
    span = np.ptp(x)
    ends = sorted(x[tips.vertices])
    assert ends[0] < x.min() + 0.05 * span and ends[1] > x.max() - 0.05 * span
    np.testing.assert_allclose(tips.distances, np.stack([rows(v) for v in tips.vertices]))


@pytest.fixture(scope="module")
def creature():
    return geodesics(datasets.creature())


def test_creature_tips_are_separated_local_maxima(creature):
    mesh, rows = creature
    tips = find_extremities(mesh, rows)
    assert 4 <= len(tips.vertices) <= 8
    separation = EXTREMITY_RADIUS * np.sqrt(mesh.area)
    between = tips.distances[:, tips.vertices]
    assert between[~np.eye(len(tips.vertices), dtype=bool)].min() >= separation
    agd = np.mean([rows(i) for i in range(mesh.n_vertices)], axis=1)
    assert np.all(agd[tips.vertices] > np.median(agd))  # tips lie far from the rest on average
    assert len(find_extremities(mesh, rows, max_count=3).vertices) == 3


def test_a_shape_onto_itself_the_identity_assignment_wins(creature):
    mesh, rows = creature
    tips = find_extremities(mesh, rows)
    assignments = match_extremities(tips, tips, n_best=3)
    assert len(assignments) == 3
    energy, pairs = assignments[0]
    assert energy == pytest.approx(0.0, abs=1e-12)
    np.testing.assert_array_equal(pairs[:, 0], pairs[:, 1])
    assert [a[0] for a in assignments] == sorted(a[0] for a in assignments)
    assert assignments[1][0] > 0


def test_fewer_than_three_tips_give_no_assignment():
    mesh, rows = geodesics(datasets.tube(n_along=24, n_around=10))
    tips = find_extremities(mesh, rows)
    assert match_extremities(tips, tips) == []
