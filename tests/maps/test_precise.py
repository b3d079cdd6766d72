"""Precise maps, functional maps and the map-quality measures (issue 14, items 3-5)."""

import numpy as np
import pytest

from meshcorr import datasets as ds
from meshcorr.errors import ParameterError
from meshcorr.evaluation.metrics import TEAR_RATIO, map_quality
from meshcorr.fmap import FunctionalMap, functional_map, point_map
from meshcorr.core.mesh import Mesh
from meshcorr.precise import precise_map, project_to_triangles


@pytest.fixture(scope="module")
def shape():
    return ds.figure()  # 448 vertices, no intrinsic symmetry to blur the bases


@pytest.fixture(scope="module")
def moved(shape):
    copy, truth = ds.rigid_copy(shape, scale=1.5, random_state=2)
    return Mesh(shape.vertices, shape.faces), Mesh(copy.vertices, copy.faces), truth


@pytest.fixture(scope="module")
def centroid_split(shape):
    """The shape with a vertex at every face centroid (1-to-3 split) and the true points on the shape."""
    V, F = shape.vertices, shape.faces
    n, m = len(V), len(F)
    centre = n + np.arange(m)
    fine_faces = np.vstack([np.c_[F[:, 0], F[:, 1], centre], np.c_[F[:, 1], F[:, 2], centre],
                            np.c_[F[:, 2], F[:, 0], centre]])
    fine = Mesh(np.vstack([V, V[F].mean(axis=1)]), fine_faces)
    vertex_map = np.concatenate([np.arange(n), F[:, 0]])  # each centroid sent to a corner of its face
    return fine, Mesh(V, F), vertex_map


def test_triangle_projection_known_answers():
    a, b, c = np.array([[0.0, 0, 0]]), np.array([[1.0, 0, 0]]), np.array([[0.0, 1, 0]])
    cases = [([0.25, 0.25, 3.0], [0.5, 0.25, 0.25], 9.0),  # above the inside: straight down
             ([2.0, -1.0, 0.0], [0.0, 1.0, 0.0], 2.0),  # beyond corner b
             ([1.0, 1.0, 0.0], [0.0, 0.5, 0.5], 0.5),  # beyond edge bc
             ([-1.0, 0.5, 0.0], [0.5, 0.0, 0.5], 1.0)]  # beyond edge ac
    for q, weights, d2 in cases:
        w, dist2 = project_to_triangles(np.array([q]), a, b, c)
        np.testing.assert_allclose(w[0], weights, atol=1e-12)
        np.testing.assert_allclose(dist2[0], d2, atol=1e-12)


def test_precise_map_of_a_reindexed_copy_lands_on_the_vertices(moved):
    source, target, truth = moved
    precise = precise_map(source, target, truth, k=30)
    np.testing.assert_array_equal(precise.vertex_map(), truth)
    assert precise.weights.max(axis=1).min() > 0.999
    np.testing.assert_allclose(precise.weights.sum(axis=1), 1.0, atol=1e-12)
    np.testing.assert_allclose(precise.points(target.vertices), target.vertices[truth], atol=1e-3)


def test_precise_map_finds_points_inside_triangles(centroid_split):
    fine, coarse, vertex_map = centroid_split
    n, m = coarse.n_vertices, len(coarse.faces)
    precise = precise_map(fine, coarse, vertex_map, k=40)
    edge = np.linalg.norm(coarse.vertices[coarse.faces[:, 0]] - coarse.vertices[coarse.faces[:, 1]], axis=1).mean()
    centre_error = np.linalg.norm(precise.points(coarse.vertices)[n:] - fine.vertices[n:], axis=1) / edge
    vertex_error = np.linalg.norm(coarse.vertices[vertex_map[n:]] - fine.vertices[n:], axis=1) / edge
    assert np.mean(precise.faces[n:] == np.arange(m)) > 0.99  # measured 0.999
    assert centre_error.mean() < 0.2 < 0.5 < vertex_error.mean()  # measured 0.14 vs 0.58 edge lengths
    inside = precise.weights[n:][precise.faces[n:] == np.arange(m)]
    assert np.abs(inside - 1 / 3).mean() < 0.15 and inside.min() > 0  # measured 0.108: well inside


def test_precise_map_interpolates_and_marks_unmapped(moved):
    source, target, truth = moved
    partial = truth.copy()
    partial[:5] = -1
    precise = precise_map(source, target, partial, k=30)
    assert (precise.faces[:5] == -1).all() and np.isnan(precise.interpolate(target.vertices[:, 0])[:5]).all()
    np.testing.assert_array_equal(precise.vertex_map()[:5], -1)
    np.testing.assert_array_equal(precise.vertex_map()[5:], truth[5:])
    np.testing.assert_allclose(precise.weights[5:].sum(axis=1), 1.0, atol=1e-12)
    with pytest.raises(ParameterError, match="'n_nearest' parameter must be an int >= 1"):
        precise_map(source, target, truth, n_nearest=0)


def test_functional_map_round_trip_on_a_permutation(moved, tmp_path):
    source, target, truth = moved
    fmap = functional_map(source, target, truth, 30)
    assert fmap.C.shape == (30, 30)
    np.testing.assert_allclose(fmap.C.T @ fmap.C, np.eye(30), atol=1e-6)  # same shape: C is orthogonal
    np.testing.assert_allclose(fmap.source_basis.T @ (fmap.source_mass[:, None] * fmap.source_basis),
                               np.eye(30), atol=1e-8)
    np.testing.assert_array_equal(fmap.point_map(), truth)
    path = tmp_path / "fmap.npz"
    fmap.save(path)
    loaded = FunctionalMap.load(path)
    np.testing.assert_array_equal(point_map(loaded.C, loaded.source_basis, loaded.target_basis), truth)
    field = target.vertices[:, 2]  # smooth: the band-limited transfer is close to the pull-back
    error = np.abs(fmap.transfer(field) - field[truth]) / np.ptp(field)
    assert error.mean() < 0.03  # measured 0.012 (a 30-function basis rings at the extremities)


def test_functional_map_errors(moved, tmp_path):
    source, target, truth = moved
    with pytest.raises(ParameterError, match="'k' parameter must be an int <="):
        functional_map(source, target, truth, 10_000)
    with pytest.raises(ParameterError, match="entries but the source mesh has"):
        functional_map(source, target, truth[:-1], 10)
    with pytest.raises(ParameterError, match="C must be"):
        point_map(np.eye(3), np.zeros((5, 4)), np.zeros((5, 3)))
    with pytest.raises(ParameterError, match="no such file"):
        FunctionalMap.load(tmp_path / "none.npz")
    np.savez(tmp_path / "bad.npz", C=np.eye(2))
    with pytest.raises(ParameterError, match="lacks the array"):
        FunctionalMap.load(tmp_path / "bad.npz")
    fmap = functional_map(source, target, truth, 5)
    np.savez(tmp_path / "shapes.npz", **{**{k: getattr(fmap, k) for k in fmap.__dataclass_fields__},
                                         "C": np.eye(4)})
    with pytest.raises(ParameterError, match="C has shape"):
        FunctionalMap.load(tmp_path / "shapes.npz")


def test_map_quality_known_answers(moved):
    source, target, truth = moved
    exact = map_quality(source, target, truth)
    assert exact["coverage"] == pytest.approx(1.0) and exact["bijectivity"] == pytest.approx(1.0)
    assert exact["continuity"] == pytest.approx(1.0, abs=1e-9) and exact["torn_edges"] == 0.0
    constant = map_quality(source, target, np.full(source.n_vertices, truth[0]))
    assert constant["bijectivity"] == pytest.approx(1 / source.n_vertices)
    assert 0 < constant["coverage"] < 0.01 and constant["continuity"] == 0.0
    rng = np.random.default_rng(0)
    scrambled = map_quality(source, target, rng.permutation(target.n_vertices))
    assert scrambled["continuity"] > TEAR_RATIO and scrambled["torn_edges"] > 0.5
    with pytest.raises(ParameterError, match="sends no source vertex"):
        map_quality(source, target, np.full(source.n_vertices, -1))


def test_a_results_precise_map_default_basis_fits_a_small_mesh():
    # The default basis (the refinement's 40 functions) is clipped as the refinement clips it;
    # a k given beyond the vertex count is refused (precise_map's own check).
    import meshcorr

    shape = ds.tube(n_along=5, n_around=6)  # 32 vertices
    result = meshcorr.match(shape, shape)
    precise = result.precise_map()
    assert precise.faces.shape == (shape.n_vertices,)
    with pytest.raises(ParameterError, match="at most n - 1 = 31"):
        result.precise_map(k=37)
