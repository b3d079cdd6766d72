"""Anchor selection, proximity-aided matching and the bijective option."""

import numpy as np
import pytest

import meshcorr.stages.anchors as anchors_module
from meshcorr.stages.anchors import anchor_descriptors, proximity_matching, select_anchors
from meshcorr.errors import ParameterError


def line(n):
    """Points on a segment; 'geodesic' distance = |x_i - x_j| / length."""
    x = np.linspace(0.0, 1.0, n)
    return x[:, None], lambda i: np.abs(x - x[i])


@pytest.fixture(params=["exact", "candidates"])
def search(request, monkeypatch):
    """Anchor selection over all pairs, or over each vertex's nearest candidates (large meshes)."""
    if request.param == "candidates":
        monkeypatch.setattr(anchors_module, "EXACT_PAIRS", 0)
    return request.param


def test_first_anchor_is_the_best_pair_and_later_ones_spread(search):
    X, g = line(50)
    Y = X.copy()
    anchors = select_anchors(X, Y, g, g, 3)
    np.testing.assert_array_equal(anchors[:, 0], anchors[:, 1])  # identical shapes: a_l == b_l
    assert len(set(anchors[:, 0])) == 3
    # Each new anchor is pushed away from the earlier ones: both ends get one.
    assert {0, 49} <= set(anchors[:, 0].tolist())


def test_later_anchors_weigh_half_of_each_geodesic_distance(search):
    # After the exact pair (0, 0), pair (i, j) scores |X_i - Y_j| - (g(0, i) + g(0, j)) / 2:
    # (1, 1) scores 0 - 0.2 = -0.2 and (2, 2) 1.2 - 1.0 = 0.2, so (1, 1) is next. With a
    # weight of 1.5 instead of 0.5, (2, 2) would score 1.2 - 3.0 = -1.8 and be chosen.
    X, Y = np.array([[0.0], [5.0], [10.0]]), np.array([[0.0], [5.0], [11.2]])
    G = np.array([[0.0, 0.2, 1.0], [0.2, 0.0, 0.8], [1.0, 0.8, 0.0]])
    np.testing.assert_array_equal(select_anchors(X, Y, G.__getitem__, G.__getitem__, 2), [[0, 0], [1, 1]])


def test_proximity_matching_on_identical_shapes_is_the_identity():
    X, g = line(40)
    F = anchor_descriptors(np.array([0, 20, 39]), g, np.ones(3))
    mapping, cost = proximity_matching(X, X, F, F)
    np.testing.assert_array_equal(mapping, np.arange(40))
    np.testing.assert_allclose(cost, 0.0, atol=1e-12)


def test_anchor_term_breaks_a_tie_in_the_embedding():
    # The embedding cannot tell the two ends apart (|x|), the anchor term can.
    x = np.linspace(-1.0, 1.0, 21)
    X = np.abs(x)[:, None]
    g = lambda i: np.abs(x - x[i]) / 2.0  # noqa: E731
    F = anchor_descriptors(np.array([0]), g, np.ones(1))
    plain, _ = proximity_matching(X, X, np.zeros((21, 0)), np.zeros((21, 0)))
    aided, _ = proximity_matching(X, X, F, F)
    assert np.mean(plain == np.arange(21)) < 1.0
    np.testing.assert_array_equal(aided, np.arange(21))


def test_bijective_map_is_the_brute_force_optimum():
    # 8 points: all 8! = 40320 one-to-one maps are scored, the cheapest is unique.
    from itertools import permutations

    rng = np.random.default_rng(0)
    X = rng.normal(size=(8, 2))
    Y = X[rng.permutation(8)] + 0.6 * rng.normal(size=(8, 2))
    empty = np.zeros((8, 0))
    mapping, cost = proximity_matching(X, Y, empty, empty, bijective=True)
    every = np.array(list(permutations(range(8))))
    totals = np.linalg.norm(X[None, :, :] - Y[every], axis=2).sum(axis=1)
    best = np.argsort(totals)[:2]
    assert totals[best[1]] > totals[best[0]] + 1e-6  # a unique optimum
    np.testing.assert_array_equal(mapping, every[best[0]])
    np.testing.assert_allclose(cost, np.linalg.norm(X - Y[mapping], axis=1), rtol=1e-12)
    greedy, _ = proximity_matching(X, Y, empty, empty)
    assert len(set(greedy.tolist())) < 8  # the argmin map is not one-to-one here


def test_bijective_map_on_a_line_is_the_sorted_matching():
    # In 1-D with cost |x - y| the sorted order matched to the sorted order is optimal,
    # so the optimum total cost is sum |sort(x) - sort(y)| (30 points: no brute force).
    rng = np.random.default_rng(1)
    x, y = rng.uniform(size=30), rng.uniform(size=30)
    empty = np.zeros((30, 0))
    mapping, cost = proximity_matching(x[:, None], y[:, None], empty, empty, bijective=True)
    assert sorted(mapping.tolist()) == list(range(30))
    np.testing.assert_allclose(cost.sum(), np.abs(np.sort(x) - np.sort(y)).sum(), rtol=1e-12)
    np.testing.assert_allclose(cost, np.abs(x - y[mapping]), rtol=1e-12)


def test_bijective_needs_equal_vertex_counts():
    X, Y = np.zeros((5, 2)), np.zeros((6, 2))
    with pytest.raises(ParameterError, match="same number of vertices; the source has 5 and the target 6"):
        proximity_matching(X, Y, np.zeros((5, 0)), np.zeros((6, 0)), bijective=True)
