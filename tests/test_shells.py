"""Shell refinement: the known map of a moved copy is its fixed point; it improves a pose map."""

import numpy as np
import pytest
from scipy.spatial import cKDTree
from scipy.spatial.transform import Rotation

from meshcorr import datasets as ds
from meshcorr.errors import ParameterError
from meshcorr.mesh import Mesh
from meshcorr.refine import refine_map
from meshcorr.shells import shell_refine


@pytest.fixture(scope="module")
def poses():
    """Two poses of one figure (same connectivity: the truth is the identity)."""
    rest, bent = ds.figure(resolution=2, pose="rest"), ds.figure(resolution=2, pose="bent")
    return Mesh(rest.vertices, rest.faces), Mesh(bent.vertices, bent.faces)


def error(mesh: Mesh, mapping: np.ndarray) -> float:
    return float(np.linalg.norm(mesh.vertices[mapping] - mesh.vertices, axis=1).mean() / np.sqrt(mesh.area))


def test_a_rotated_scaled_reindexed_copy_maps_by_its_permutation(poses):
    rest = poses[0]
    rng = np.random.default_rng(3)
    order = rng.permutation(rest.n_vertices)  # copy vertex j is rest vertex order[j]
    inverse = np.argsort(order)
    moved = Rotation.from_rotvec([0.4, -1.1, 0.7]).apply(rest.vertices[order]) * 2.5 + [3.0, -1.0, 0.5]
    copy = Mesh(moved, inverse[rest.faces])
    # From a map that is wrong on 10 % of the vertices (each sent to a vertex nearby), the
    # shells return the permutation itself: with the same bases the deformation is the motion.
    start = inverse.copy()
    wrong = rng.choice(rest.n_vertices, size=rest.n_vertices // 10, replace=False)
    start[wrong] = inverse[cKDTree(rest.vertices).query(rest.vertices[wrong], k=4)[1][:, 3]]
    refined = shell_refine(rest, copy, start, k=30)
    assert np.mean(refined == inverse) > 0.99
    assert np.array_equal(shell_refine(rest, copy, inverse, k=30), inverse)


def test_shells_lower_the_error_of_the_zoomout_map_of_a_bent_pose(poses):
    rest, bent = poses
    rng = np.random.default_rng(0)
    jitter = rng.normal(0.0, 0.03 * np.sqrt(bent.area), bent.vertices.shape)
    start = cKDTree(bent.vertices).query(bent.vertices + jitter)[1]
    zoomed, _ = refine_map(rest, bent, start, k=30)
    shelled = shell_refine(rest, bent, zoomed, k=30)
    assert error(bent, shelled) < 0.8 * error(bent, zoomed), (error(bent, zoomed), error(bent, shelled))
    assert np.array_equal(shelled, shell_refine(rest, bent, zoomed, k=30))  # same seed, same map


def test_landmarks_are_held(poses):
    rest, bent = poses
    pairs = np.array([[0, 5], [10, 40]])
    mapping = shell_refine(rest, bent, np.arange(rest.n_vertices), k=20, landmarks=pairs)
    assert mapping[0] == 5 and mapping[10] == 40


def test_bad_inputs_are_refused(poses):
    rest, bent = poses
    with pytest.raises(ParameterError, match="one target vertex"):
        shell_refine(rest, bent, np.zeros(3, dtype=int))
    with pytest.raises(ParameterError, match="one target vertex"):
        shell_refine(rest, bent, np.full(rest.n_vertices, bent.n_vertices))
    cloud = Mesh(bent.vertices, np.zeros((0, 3), dtype=int))
    with pytest.raises(ParameterError, match="point clouds"):
        shell_refine(rest, cloud, np.arange(rest.n_vertices))
