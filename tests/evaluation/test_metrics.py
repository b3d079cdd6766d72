"""Evaluation (meshcorr.evaluation.metrics): geodesic errors against known answers, flips, curves."""

import numpy as np
import pytest
from scipy.spatial import cKDTree

from meshcorr import datasets as ds
from meshcorr.errors import ParameterError
from meshcorr.evaluation.metrics import (GeodesicCache, _greedy_cover, cumulative_curve, evaluate_map,
                                 feature_point_accuracy, geodesic_errors, scalar_summary)
from meshcorr.evaluation.ground_truth import GroundTruth, identity_truth
from meshcorr.core.mesh import Mesh

RADIUS = 2.0


@pytest.fixture(scope="module")
def sphere():
    vertices, faces = ds.sphere(subdivisions=3, radius=RADIUS)  # 642 vertices
    return Mesh(vertices, faces, name="sphere")


def great_circle(vertices, i, j):
    cosine = np.einsum("ij,ij->i", vertices[i], vertices[j]) / RADIUS**2
    return RADIUS * np.arccos(np.clip(cosine, -1.0, 1.0))


def rotated_map(vertices, angle):
    """Each vertex -> the vertex nearest to it rotated by ``angle`` about z."""
    c, s = np.cos(angle), np.sin(angle)
    rotation = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    return cKDTree(vertices).query(vertices @ rotation.T)[1]


def mirror_map(vertices):
    """Each vertex -> its mirror image in the plane x = 0 (exact on the icosphere)."""
    distance, index = cKDTree(vertices).query(vertices * [-1.0, 1.0, 1.0])
    assert distance.max() < 1e-9
    return index


def test_sphere_error_equals_great_circle_distance(sphere):
    # Independent answer: the great-circle distance R*arccos(<p, q>/R^2) over sqrt(4 pi R^2).
    mapping = rotated_map(sphere.vertices, 1.0)
    n = sphere.n_vertices
    report = evaluate_map(sphere, mapping, identity_truth(n, n))
    expected = great_circle(sphere.vertices, mapping, np.arange(n)) / np.sqrt(4 * np.pi * RADIUS**2)
    # heat method: ~1-2 % low on a 642-vertex sphere (DEPENDENCIES.md); the mesh area is 0.5 % low
    np.testing.assert_allclose(report["mean_error"], expected.mean(), rtol=0.03)
    np.testing.assert_allclose(report["errors"], expected, atol=0.01)
    np.testing.assert_allclose(report["total_error"], report["total_error_normalized"] * report["sqrt_area"],
                               rtol=1e-12)
    np.testing.assert_allclose(report["total_error"], great_circle(sphere.vertices, mapping, np.arange(n)).sum(),
                               rtol=0.03)


def test_fmm_agrees_with_great_circle(sphere):
    mapping = rotated_map(sphere.vertices, 0.8)[:60]
    errors = geodesic_errors(sphere, mapping, np.arange(60), method="fmm", normalize=False)
    # fast marching overestimates by up to ~6 % on this coarse (642-vertex) sphere
    np.testing.assert_allclose(errors, great_circle(sphere.vertices, mapping, np.arange(60)), rtol=0.08)


def test_identity_map_has_zero_error_without_solves(sphere):
    n = sphere.n_vertices
    cache = GeodesicCache()
    report = evaluate_map(sphere, np.arange(n), identity_truth(n, n), cache=cache)
    assert report["mean_error"] == 0.0 and report["total_error"] == 0.0
    assert report["under"] == {"0.05": 1.0, "0.1": 1.0, "0.25": 1.0}
    assert cache.n_solves == 0


def test_flip_verdict_on_mirrored_map(sphere):
    n = sphere.n_vertices
    mirror = mirror_map(sphere.vertices)
    truth, sym = identity_truth(n, n), GroundTruth(np.arange(n), mirror, "mirror")
    cache = GeodesicCache()
    flipped = evaluate_map(sphere, mirror, truth, sym_truth=sym, cache=cache)
    assert flipped["flipped"] is True
    assert flipped["sym_mean_error"] == 0.0 and flipped["best_mean_error"] == 0.0
    assert flipped["mean_error"] > 0.1
    solves = cache.n_solves
    direct = evaluate_map(sphere, np.arange(n), truth, sym_truth=sym, cache=cache)
    assert direct["flipped"] is False and direct["mean_error"] == 0.0
    np.testing.assert_allclose(direct["sym_mean_error"], flipped["mean_error"], rtol=0.05)
    assert cache.n_solves - solves < n // 4  # rows solved for the first map serve the second
    assert "errors" not in scalar_summary(direct) and "flipped" in scalar_summary(direct)


def test_cumulative_curve_known_values_and_monotone():
    thresholds, fractions = cumulative_curve(np.array([0.0, 0.1, 0.2, np.nan]), [0.0, 0.05, 0.1, 0.25])
    np.testing.assert_allclose(fractions, [0.25, 0.25, 0.5, 0.75])
    thresholds, fractions = cumulative_curve(np.random.default_rng(0).random(500) * 0.3)
    assert thresholds[0] == 0.0 and thresholds[-1] == 0.25 and len(thresholds) == 101
    assert np.all(np.diff(fractions) >= 0)
    np.testing.assert_allclose(fractions[-1], 0.25 / 0.3, atol=0.05)
    assert cumulative_curve(np.array([]))[1].sum() == 0.0


def test_feature_point_accuracy_counts_points_within_tolerance(sphere):
    n = sphere.n_vertices
    points = np.arange(0, n, 40)
    mapping = np.arange(n)
    mapping[points[:4]] = mirror_map(sphere.vertices)[points[:4]]  # 4 wrong (unless on the mirror plane)
    wrong = np.count_nonzero(mapping[points] != points)
    truth = GroundTruth(points, points, "features")
    accuracy = feature_point_accuracy(sphere, mapping, truth, tolerance=0.01)
    np.testing.assert_allclose(accuracy, 1 - wrong / len(points))
    assert wrong >= 3


def test_unmapped_points_are_misses_not_means(sphere):
    n = sphere.n_vertices
    mapping = np.arange(n)
    mapping[:10] = -1
    report = evaluate_map(sphere, mapping, identity_truth(n, n))
    assert report["n_unmapped"] == 10 and report["mean_error"] == 0.0
    np.testing.assert_allclose(report["under"]["0.05"], 1 - 10 / n)
    assert np.isnan(report["errors"][:10]).all()


def test_cache_is_keyed_on_content_not_object(sphere):
    cache = GeodesicCache()
    a, b = np.array([0, 1, 2]), np.array([5, 6, 7])
    first = cache.pair_distances(sphere, a, b)
    solves = cache.n_solves
    twin = Mesh(sphere.vertices.copy(), sphere.faces.copy())
    np.testing.assert_array_equal(cache.pair_distances(twin, b, a), first)
    assert cache.n_solves == solves
    moved = Mesh(sphere.vertices * 2.0, sphere.faces)
    np.testing.assert_allclose(cache.pair_distances(moved, a, b), 2 * first, rtol=1e-5)
    assert cache.n_solves > solves


def test_greedy_cover_touches_every_pair():
    rng = np.random.default_rng(1)
    a, b = rng.integers(0, 50, 300), rng.integers(0, 50, 300)
    cover = set(_greedy_cover(a, b).tolist())
    assert all(x in cover or y in cover for x, y in zip(a, b))
    star = _greedy_cover(np.zeros(20, dtype=int), np.arange(1, 21))
    np.testing.assert_array_equal(star, [0])  # the hub covers all 20 pairs


def test_map_errors(sphere):
    n = sphere.n_vertices
    truth = identity_truth(n, n)
    with pytest.raises(ParameterError, match="only 5 entries"):
        evaluate_map(sphere, np.arange(5), truth)
    bad = np.arange(n)
    bad[3] = n
    with pytest.raises(ParameterError, match="Map entry 3"):
        evaluate_map(sphere, bad, truth)
    with pytest.raises(ParameterError, match="1-D integer"):
        evaluate_map(sphere, np.zeros((n, 2), dtype=int), truth)
    with pytest.raises(ParameterError, match="target vertex"):
        evaluate_map(sphere, np.arange(n), GroundTruth([0], [n + 3]))
    with pytest.raises(ParameterError, match="'heat' geodesics"):
        evaluate_map(sphere, np.arange(n), truth, geodesic="fmm", cache=GeodesicCache("heat"))
    with pytest.raises(ParameterError, match="'geodesic' parameter"):
        GeodesicCache("nope")


# ---------------------------------------------------------------- ground-truth files


def test_a_cache_reports_its_solves_and_keeps_the_same_rows(sphere):
    calls = []
    rng = np.random.default_rng(4)
    a, b = rng.integers(0, len(sphere.vertices), size=(2, 300))
    quiet = GeodesicCache().pair_distances(sphere, a, b)
    cache = GeodesicCache(progress=lambda *call: calls.append(call))
    np.testing.assert_array_equal(cache.pair_distances(sphere, a, b), quiet)
    assert {stage for stage, _, _ in calls} == {"geodesic errors"}
    done = [d for _, d, _ in calls]
    assert done[0] == 0 and done[-1] == cache.n_solves > 0 and done == sorted(done) and len(done) > 10
    assert all(total == cache.n_solves for _, _, total in calls)
    # reporting(): another callback for a block, then the cache's own again; cached rows report nothing.
    other, later = [], []
    with cache.reporting(lambda *call: other.append(call)):
        cache.pair_distances(sphere, a, b)
        cache.pair_distances(sphere, (a[:5] + 1) % len(sphere.vertices), (b[:5] + 2) % len(sphere.vertices))
    assert cache.progress is not None and other and other[-1][1] == other[-1][2]
    calls.clear()
    cache.pair_distances(sphere, a, b)
    assert calls == []
