"""meshcorr.stages.tps: thin-plate splines interpolate, reproduce affine maps and match scipy's RBFInterpolator."""

import numpy as np
import pytest
from scipy.interpolate import RBFInterpolator
from scipy.spatial.distance import pdist

from meshcorr.stages.tps import fit_tps, mean_pairwise_distance


@pytest.fixture(scope="module")
def points():
    rng = np.random.default_rng(1)
    return rng.normal(size=(40, 5)), rng.normal(size=(40, 5)), rng.normal(size=(300, 5))


def test_interpolates_without_smoothing(points):
    sources, destinations, _ = points
    spline = fit_tps(sources, destinations, 0.0)
    np.testing.assert_allclose(spline(sources), destinations, atol=1e-9)


def test_affine_maps_are_reproduced_exactly_for_any_smoothing(points):
    sources, _, others = points
    rng = np.random.default_rng(2)
    A, b = rng.normal(size=(5, 5)), rng.normal(size=5)
    for smoothing in (0.0, 1.0, 1e3):
        spline = fit_tps(sources, sources @ A + b, smoothing)
        np.testing.assert_allclose(spline(others), others @ A + b, atol=1e-8)
        np.testing.assert_allclose(spline.weights, 0.0, atol=1e-9)


def test_same_values_as_scipy(points):
    sources, destinations, others = points
    spline = fit_tps(sources, destinations, 0.5)
    reference = RBFInterpolator(sources, destinations, kernel="linear", degree=1, smoothing=0.5)
    np.testing.assert_allclose(spline(others), reference(others), atol=1e-10)


def test_large_smoothing_tends_to_the_least_squares_affine_map(points):
    sources, destinations, others = points
    design = np.column_stack([np.ones(len(sources)), sources])
    coefficients = np.linalg.lstsq(design, destinations, rcond=None)[0]
    spline = fit_tps(sources, destinations, 1e9)
    np.testing.assert_allclose(spline(others), np.column_stack([np.ones(len(others)), others]) @ coefficients,
                               atol=1e-4)


def test_blocks_do_not_change_the_values(points, monkeypatch):
    import meshcorr.stages.tps as tps

    sources, destinations, others = points
    spline = fit_tps(sources, destinations, 0.1)
    whole = spline(others)
    monkeypatch.setattr(tps, "_EVAL_BLOCK", 7)
    np.testing.assert_array_equal(spline(others), whole)


def test_mean_pairwise_distance():
    square = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    assert mean_pairwise_distance(square) == pytest.approx((4 + 2 * np.sqrt(2)) / 6)
    assert mean_pairwise_distance(square[:1]) == 0.0
    many = np.random.default_rng(0).uniform(size=(3000, 2))
    estimate = mean_pairwise_distance(many, max_points=2000, random_state=4)
    assert estimate == pytest.approx(pdist(many[::3]).mean(), rel=0.02)  # sampled, close to the whole mean
    assert estimate == mean_pairwise_distance(many, max_points=2000, random_state=4)
