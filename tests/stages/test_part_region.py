"""meshcorr.stages.part_region: the region of the whole a part's map covers, its area share and the inverse map."""

import numpy as np
import pytest

from meshcorr import datasets as ds
from meshcorr.core.mesh import as_mesh
from meshcorr.stages.part_region import area_fraction, invert_part_map, matched_region


@pytest.fixture(scope="module")
def cap():
    V, F = ds.sphere(subdivisions=4)
    return as_mesh((V, F)), np.flatnonzero(V[:, 2] > 0.2)


def test_matched_region_fills_the_gaps_of_a_map_and_keeps_the_outline(cap):
    ball, upper = cap
    V = ball.vertices
    images = upper[::3]  # a map that is not onto: a third of the upper cap
    region = matched_region(ball, images, reach=0.05, closing=0.15)
    assert region[upper].mean() > 0.97  # the gaps are filled
    assert (V[region, 2] > 0.05).all()  # the outline did not grow by more than the reach


def test_the_area_share_of_a_spherical_cap(cap):
    ball, upper = cap
    mask = np.zeros(ball.n_vertices, dtype=bool)
    assert area_fraction(ball, ~mask) == pytest.approx(1.0)
    mask[upper] = True
    assert area_fraction(ball, mask) == pytest.approx((1 - 0.2) / 2, rel=0.05)  # Archimedes: (1 - h) / 2


def test_the_inverse_map_is_defined_on_the_region_only(cap):
    ball, upper = cap
    region = np.zeros(ball.n_vertices, dtype=bool)
    region[upper] = True
    inverse = invert_part_map(ball, upper, region)  # part vertex i is whole vertex upper[i]
    np.testing.assert_array_equal(inverse[upper], np.arange(len(upper)))
    assert (inverse[~region] == -1).all()
