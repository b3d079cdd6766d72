"""Thin-plate splines and TPS-ICP in the spectral domain."""

import numpy as np
import pytest
from scipy.spatial import cKDTree

from meshcorr.errors import ParameterError
from meshcorr.stages.icp import tps_icp
from meshcorr.stages.tps import fit_tps, mean_pairwise_distance


def test_tps_interpolates_without_smoothing():
    rng = np.random.default_rng(0)
    src = rng.normal(size=(40, 5))
    dst = src + 0.1 * np.sin(src)
    f = fit_tps(src, dst, smoothing=0.0)
    np.testing.assert_allclose(f(src), dst, atol=1e-8)


def test_tps_is_affine_under_heavy_smoothing():
    rng = np.random.default_rng(1)
    src = rng.normal(size=(60, 3))
    A = np.array([[1.2, 0.1, 0.0], [0.0, 0.9, 0.2], [0.1, 0.0, 1.1]])
    dst = src @ A + np.array([0.5, -0.2, 0.3]) + 0.05 * rng.normal(size=src.shape)
    f = fit_tps(src, dst, smoothing=1e9)
    query = rng.normal(size=(10, 3))
    coef, *_ = np.linalg.lstsq(np.c_[np.ones(60), src], dst, rcond=None)
    np.testing.assert_allclose(f(query), np.c_[np.ones(10), query] @ coef, atol=1e-4)


def test_mean_pairwise_distance_known_answer():
    points = np.array([[0.0, 0.0], [3.0, 4.0], [0.0, 4.0]])
    assert mean_pairwise_distance(points) == pytest.approx((5 + 4 + 3) / 3)


def test_icp_undoes_a_smooth_warp():
    rng = np.random.default_rng(2)
    t = rng.uniform(0, 2 * np.pi, size=800)
    X = np.c_[np.cos(t), np.sin(t), 0.3 * np.cos(2 * t), 0.1 * np.sin(3 * t)] * [1.0, 0.6, 1.0, 1.0]
    Y = X * [1.1, 0.9, 1.0, 1.0] + 0.05 * X[:, [1, 0, 3, 2]] ** 2  # stretched copy, same order
    before = cKDTree(Y).query(X)[0].mean()
    result = tps_icp(X, Y, max_iter=10, random_state=0)
    after = cKDTree(result.warped).query(X)[0].mean()
    assert after < 0.25 * before
    # The warp also moves each point towards its own partner.
    assert np.linalg.norm(X - result.warped, axis=1).mean() < 0.6 * np.linalg.norm(X - Y, axis=1).mean()
    assert result.converged and len(result.history) <= 10
    costs = [h["cost"] for h in result.history]
    assert costs[-1] < costs[0]
    # Many matches change at first, fewer than tol (3 %) when it stops: measured 0.278
    # falling to 0.015 over 7 iterations.
    changed = [h["changed"] for h in result.history]
    assert changed[0] > 0.2 and changed[-1] < 0.03, changed


def test_zero_iterations_leave_the_target_unchanged():
    X = np.random.default_rng(3).normal(size=(50, 3))
    result = tps_icp(X, X + 1.0, max_iter=0)
    np.testing.assert_array_equal(result.warped, X + 1.0)
    assert result.history == []


@pytest.mark.parametrize("kwargs, message", [
    ({"max_iter": -1}, "'icp_iterations' parameter must be an int >= 0"),
    ({"anneal": 0.0}, "'anneal' parameter must be a number > 0"),
    ({"anneal": 1.5}, "'anneal' parameter must be a number <= 1"),
])
def test_bad_parameters_are_rejected(kwargs, message):
    X = np.zeros((20, 3))
    with pytest.raises(ParameterError, match=message):
        tps_icp(X, X, **kwargs)


@pytest.mark.parametrize("smoothing", [0.0, 0.3, 1e6])
def test_tps_equals_scipy_rbf_interpolator(smoothing):
    """The hand-written spline is scipy's RBFInterpolator(kernel="linear", degree=1) (issue 5)."""
    from scipy.interpolate import RBFInterpolator

    rng = np.random.default_rng(5)
    src = rng.normal(size=(120, 5)) * [1.0, 0.5, 0.3, 0.2, 0.1]
    dst = src + 0.1 * np.sin(3 * src)
    query = rng.normal(size=(20_000, 5)) * 0.5  # more than one evaluation block
    reference = RBFInterpolator(src, dst, kernel="linear", degree=1, smoothing=smoothing)(query)
    np.testing.assert_allclose(fit_tps(src, dst, smoothing)(query), reference, rtol=0, atol=1e-9)


def test_icp_keeps_the_last_warp_when_the_pairs_are_affinely_dependent():
    # A tiny symmetric mesh (a 12-vertex hexagonal prism) has a flat embedding: its spline system is
    # singular, which was an internal error (LinAlgError: Singular matrix).
    rng = np.random.default_rng(0)
    flat = np.zeros((12, 5))
    flat[:, :2] = rng.normal(size=(12, 2))  # 12 points spanning 2 of 5 dimensions
    result = tps_icp(flat, flat[::-1].copy(), n_control=12)
    np.testing.assert_array_equal(result.warped, flat[::-1])
    assert result.history == [] and result.spline is None


def test_a_bad_control_point_count_names_its_flag():
    with pytest.raises(ParameterError, match=r"'n_control' parameter \(--control-points\) must be an int >= 7"):
        tps_icp(np.zeros((10, 5)), np.zeros((10, 5)), n_control=3)
