"""Speed-ups of the stages before the refinement keep their results (issue 5)."""

from __future__ import annotations

import numpy as np
import pytest

from meshcorr import datasets as ds
from meshcorr.core.mesh import Mesh
from meshcorr.core.map_orientation import orientation_score


@pytest.fixture(scope="module")
def creature_pair():
    rest, bent = ds.creature(resolution=1), ds.creature(resolution=1, pose="bent")
    return (rest.vertices, rest.faces), (bent.vertices, bent.faces)


def test_cached_orientation_score_equals_a_fresh_computation(creature_pair):
    """Scores from the per-mesh cache equal those computed on fresh meshes, map after map."""
    (V1, F1), (V2, F2) = creature_pair
    source, target = Mesh(V1, F1), Mesh(V2, F2)
    rng = np.random.default_rng(0)
    maps = [np.arange(len(V1)), rng.integers(0, len(V2), size=len(V1)),
            np.roll(np.arange(len(V1)), 7)]
    for mapping in maps:
        for n_sample in (50, 10_000):
            cached = orientation_score(source, target, mapping, n_sample=n_sample, random_state=3)
            fresh = orientation_score(Mesh(V1, F1), Mesh(V2, F2), mapping, n_sample=n_sample, random_state=3)
            assert cached == fresh
    assert orientation_score(source, target, maps[0]) > 0.95


def test_unseeded_orientation_sample_is_not_cached(creature_pair):
    (V1, F1), _ = creature_pair
    mesh = Mesh(V1, F1)
    orientation_score(mesh, mesh, np.arange(len(V1)), n_sample=20, random_state=None)
    assert not any(key[0] == "orientation_neighbourhoods" for key in mesh.store)


def test_signed_volumes_equal_the_direct_sum_from_each_origin(creature_pair):
    """One pass over the faces gives the divergence-theorem volume seen from any origin."""
    from meshcorr.core.orientation import _signed_volumes

    (V, F), _ = creature_pair
    open_faces = F[: len(F) // 2]  # a large hole: the volume depends on the origin
    origins = np.array([[0.0, 0.0, 0.0], [3.0, -2.0, 1.0], [-5.0, 4.0, 2.5]])
    for faces in (F, open_faces):
        direct = []
        for o in origins:
            v = V[faces] - o
            direct.append(np.einsum("ij,ij->i", v[:, 0], np.cross(v[:, 1], v[:, 2])).sum() / 6.0)
        np.testing.assert_allclose(_signed_volumes(V, faces, origins), direct, rtol=1e-10, atol=1e-12)
    volumes = _signed_volumes(V, open_faces, origins)
    assert np.ptp(volumes) > 0.1 * np.abs(volumes).max()  # the open case really differs


def test_shared_neighbours_give_the_same_anchors_and_map():
    """Steps 6-7 may share one k-NN query (embedding_neighbours): same results as without it."""
    from scipy.spatial import cKDTree

    from meshcorr.stages.anchors import EXACT_PAIRS, embedding_neighbours, proximity_matching, select_anchors

    rng = np.random.default_rng(0)
    X, Y = rng.normal(size=(2100, 5)), rng.normal(size=(2100, 5))
    assert len(X) * len(Y) > EXACT_PAIRS  # the candidate (KD-tree) path
    rows = lambda i: np.linalg.norm(X - X[i], axis=1)  # noqa: E731
    cols = lambda j: np.linalg.norm(Y - Y[j], axis=1)  # noqa: E731
    shared = embedding_neighbours(X, Y)
    assert shared[0].shape == shared[1].shape == (len(X), 16)
    np.testing.assert_array_equal(select_anchors(X, Y, rows, cols, 2, neighbours=shared),
                                  select_anchors(X, Y, rows, cols, 2))
    empty = np.zeros((len(X), 0))
    mapping, cost = proximity_matching(X, Y, empty, np.zeros((len(Y), 0)), neighbours=shared)
    dist, expected = cKDTree(Y).query(X)
    np.testing.assert_array_equal(mapping, expected)
    np.testing.assert_allclose(cost, dist, rtol=1e-12)


def test_orientation_scores_equal_the_two_scores_and_cache_the_regions(creature_pair):
    from meshcorr.core.map_orientation import orientation_scores, regional_orientation

    (V1, F1), (V2, F2) = creature_pair
    source, target = Mesh(V1, F1), Mesh(V2, F2)
    rng = np.random.default_rng(0)
    for mapping in (np.arange(len(V1)), rng.integers(0, len(V2), size=len(V1))):
        score, regional = orientation_scores(source, target, mapping, random_state=3)
        assert score == orientation_score(Mesh(V1, F1), Mesh(V2, F2), mapping, random_state=3)
        np.testing.assert_array_equal(regional, regional_orientation(Mesh(V1, F1), Mesh(V2, F2), mapping,
                                                                     random_state=3))
    assert any(key[0] == "orientation_regions" for key in source.store)
    with pytest.raises(Exception, match="one entry per source vertex"):
        orientation_scores(source, target, np.arange(3))
    unseeded = Mesh(V1, F1)
    orientation_scores(unseeded, unseeded, np.arange(len(V1)), random_state=None)
    assert not any(key[0] == "orientation_regions" for key in unseeded.store)
