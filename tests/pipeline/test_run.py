"""End-to-end invariances of meshcorr.match."""

import time

import numpy as np
import pytest
import trimesh

import meshcorr
from meshcorr import datasets as ds
from meshcorr.errors import MeshError, ParameterError


@pytest.fixture(scope="module")
def shape():
    return ds.tube(n_along=26, n_around=12)  # ~330 vertices, bumps make it asymmetric


@pytest.fixture(scope="module")
def copy_and_truth(shape):
    return ds.rigid_copy(shape, scale=3.7, random_state=5)


@pytest.fixture(scope="module")
def timed_result(shape, copy_and_truth):
    """The match of the copy and the seconds the call took."""
    copy, _ = copy_and_truth
    start = time.perf_counter()
    result = meshcorr.match((shape.vertices, shape.faces), (copy.vertices, copy.faces), random_state=0)
    return result, time.perf_counter() - start


@pytest.fixture(scope="module")
def result(timed_result):
    return timed_result[0]


def test_rotated_scaled_reindexed_copy_maps_to_the_permutation(result, copy_and_truth):
    _, truth = copy_and_truth
    np.testing.assert_array_equal(result.map, truth)


def test_result_holds_every_stage(timed_result, shape):
    result, seconds = timed_result
    n = shape.n_vertices
    assert result.method == "spectral"
    assert result.map.shape == (n,) and result.map.dtype == np.int64
    assert result.source_embedding.shape == (n, 5)
    assert result.aligned_target_embedding.shape == (n, 5)
    assert result.eigenvalues["source"].shape == (6,)
    assert np.all(np.diff(result.eigenvalues["source"]) <= 0)
    assert result.alternatives[0] == result.configuration
    assert result.runner_up.cost >= result.configuration.cost
    assert result.anchors.shape == (3, 2)
    assert set(result.timings) >= {"load", "geodesics", "embedding", "reorder", "icp", "matching"}
    # The stages are disjoint parts of the call and cover nearly all of it (measured 96-97 %;
    # the lower bound only catches a wrong unit).
    assert 0.2 * seconds <= sum(result.timings.values()) <= seconds
    summary = result.summary()
    assert summary["n_mapped"] == n and summary["configuration"]["cost"] == pytest.approx(0.0, abs=1e-9)


def test_eigenvalues_are_invariant_to_rigid_motion_and_scale(result):
    np.testing.assert_allclose(result.eigenvalues["source"], result.eigenvalues["target"], rtol=1e-6)


def test_same_seed_same_map_and_bijective_is_a_permutation(shape, copy_and_truth):
    copy, truth = copy_and_truth
    source, target = (shape.vertices, shape.faces), (copy.vertices, copy.faces)
    a = meshcorr.match(source, target, reorder="greedy", bijective=True, random_state=3)
    b = meshcorr.match(source, target, reorder="greedy", bijective=True, random_state=3)
    np.testing.assert_array_equal(a.map, b.map)
    np.testing.assert_array_equal(a.map, truth)


def test_accepts_paths_and_trimesh_objects(tmp_path, shape, copy_and_truth):
    copy, truth = copy_and_truth
    path = tmp_path / "source.off"
    trimesh.Trimesh(shape.vertices, shape.faces, process=False).export(path)
    target = trimesh.Trimesh(copy.vertices, copy.faces, process=False)
    res = meshcorr.match(str(path), target, reorder="greedy")
    np.testing.assert_array_equal(res.map, truth)


def test_largest_component_maps_only_the_kept_vertices(shape):
    # Add a small detached tetrahedron to the source.
    tet = trimesh.creation.box().vertices[:4] * 0.1 + 10.0
    V = np.vstack([shape.vertices, tet])
    F = np.vstack([shape.faces, np.array([[0, 1, 2], [0, 3, 1], [0, 2, 3], [1, 3, 2]]) + shape.n_vertices])
    with pytest.raises(MeshError, match="largest"):
        meshcorr.match((V, F), (shape.vertices, shape.faces))
    res = meshcorr.match((V, F), (shape.vertices, shape.faces), largest_component=True, reorder="greedy")
    np.testing.assert_array_equal(res.map[-4:], -1)
    np.testing.assert_array_equal(res.map[:-4], np.arange(shape.n_vertices))
    np.testing.assert_array_equal(res.source_vertices, np.arange(shape.n_vertices))


def test_too_few_vertices_names_k():
    tet = trimesh.creation.box()  # 8 vertices
    with pytest.raises(MeshError, match=r"at least 10 are needed: the spectral embedding with k=8 \(-k\)"):
        meshcorr.match((tet.vertices, tet.faces), (tet.vertices, tet.faces), k=8)


@pytest.mark.parametrize("kwargs, message", [
    ({"k": 1}, "'k' parameter must be an int >= 2"),
    ({"k": 2.5}, "'k' parameter must be an int"),
    ({"geodesic": "euclid"}, "'geodesic' parameter must be one of"),
    ({"reorder": "best"}, "'reorder' parameter must be one of"),
    ({"n_anchors": -1}, r"'n_anchors' parameter \(--anchors\) must be an int >= 0"),
    ({"anchor_weight": -0.5}, r"'anchor_weight' parameter \(--alpha\) must be a number >= 0"),
])
def test_bad_options_are_rejected(shape, kwargs, message):
    with pytest.raises(ParameterError, match=message):
        meshcorr.match((shape.vertices, shape.faces), (shape.vertices, shape.faces), **kwargs)


def test_bijective_with_different_vertex_counts_is_an_error(shape):
    other = ds.tube(n_along=20, n_around=12)
    with pytest.raises(ParameterError, match="bijective"):
        meshcorr.match((shape.vertices, shape.faces), (other.vertices, other.faces), bijective=True)


def test_unknown_input_type_is_an_error():
    with pytest.raises(MeshError, match="Cannot make a mesh out of int"):
        meshcorr.match(3, 4)


@pytest.fixture(scope="module")
def creature_rest():
    return ds.creature(resolution=1)


@pytest.mark.parametrize("pose, resolution", [("bent", 1), ("curled", 1), ("bent", 2)])
def test_bent_pose_maps_back_with_small_geodesic_error(creature_rest, pose, resolution):
    """An isometric bend, also at another resolution (different vertex count)."""
    from meshcorr.evaluation.metrics import geodesic_errors

    target = ds.creature(resolution=resolution, pose=pose, random_state=1)
    truth = ds.ground_truth(creature_rest, target)
    res = meshcorr.match((creature_rest.vertices, creature_rest.faces), (target.vertices, target.faces))
    errors = geodesic_errors((target.vertices, target.faces), res.map, truth)
    # Measured 0.023-0.032; a mirrored or scrambled map scores > 0.2.
    assert errors.mean() < 0.05
    assert res.icp_converged and len(res.icp_history) <= 10


def hexagonal_prism(height: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """A closed hexagonal prism of 12 vertices and 20 faces (caps fanned from a corner)."""
    angles = np.arange(6) * np.pi / 3
    ring = np.c_[np.cos(angles), np.sin(angles), np.zeros(6)]
    vertices = np.vstack([ring, ring + [0.0, 0.0, height]])
    faces = [[i, (i + 1) % 6, 6 + (i + 1) % 6] for i in range(6)] + [[i, 6 + (i + 1) % 6, 6 + i] for i in range(6)]
    faces += [[0, t + 1, t] for t in range(1, 5)] + [[6, 6 + t, 7 + t] for t in range(1, 5)]
    return vertices, np.array(faces)


def test_a_tiny_closed_mesh_is_matched():
    # Its flat embedding made the spline system of the ICP singular (an internal error, issue 31 item 16).
    source, target = hexagonal_prism(), hexagonal_prism(1.5)
    mapping = meshcorr.match(source, target).map
    assert mapping.shape == (12,) and mapping.min() >= 0 and mapping.max() < 12
