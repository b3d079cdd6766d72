"""Tests of the synthetic shapes and their ground truth (meshcorr.datasets)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import trimesh
from scipy.spatial import cKDTree

from meshcorr import datasets
from meshcorr.evaluation.datasets import capsule
from meshcorr.evaluation.datasets import creatures as creature_module
from meshcorr.datasets import (
    SyntheticShape,
    creature,
    figure,
    ground_truth,
    rigid_copy,
    sphere,
    tube,
)
from meshcorr.errors import MeshError, ParameterError

# two resolutions x two poses for each generator
TUBES = {
    ("coarse", "straight"): dict(n_along=12, n_around=14),
    ("coarse", "bent"): dict(n_along=12, n_around=14, bend=np.pi / 2),
    ("fine", "straight"): dict(n_along=60, n_around=24),
    ("fine", "bent"): dict(n_along=60, n_around=24, bend=-np.pi),
}
FIGURES = {
    ("coarse", "rest"): dict(resolution=1, pose="rest"),
    ("coarse", "curled"): dict(resolution=1, pose="curled"),
    ("fine", "rest"): dict(resolution=3, pose="rest"),
    ("fine", "bent"): dict(resolution=3, pose="bent"),
}
CASES = [(tube, kw) for kw in TUBES.values()] + [(figure, kw) for kw in FIGURES.values()]
CASE_IDS = [f"tube-{a}-{b}" for a, b in TUBES] + [f"figure-{a}-{b}" for a, b in FIGURES]


def _mesh(shape: SyntheticShape) -> trimesh.Trimesh:
    return trimesh.Trimesh(shape.vertices, shape.faces, process=False)


def _edge_lengths(shape: SyntheticShape, edges: np.ndarray) -> np.ndarray:
    return np.linalg.norm(shape.vertices[edges[:, 0]] - shape.vertices[edges[:, 1]], axis=1)


def _chart_points(shape: SyntheticShape) -> np.ndarray:
    t = shape.params[:, 0]
    return capsule.chart_embedding(shape.params, t.min(), t.max())


@pytest.mark.parametrize(("make", "kwargs"), CASES, ids=CASE_IDS)
def test_closed_oriented_manifold(make, kwargs):
    shape = make(**kwargs)
    mesh = _mesh(shape)
    assert shape.vertices.dtype == np.float64 and shape.vertices.shape[1] == 3
    assert shape.faces.dtype == np.int64 and shape.params.shape == (shape.n_vertices, 2)
    assert mesh.is_watertight  # every edge in exactly two faces
    assert mesh.is_winding_consistent
    assert mesh.volume > 0  # outward normals
    assert mesh.body_count == 1
    assert mesh.euler_number == 2  # a sphere topologically
    assert len(np.unique(shape.faces.ravel())) == shape.n_vertices  # no unused vertex
    assert len(np.unique(np.sort(shape.faces, axis=1), axis=0)) == len(shape.faces)
    assert np.degrees(mesh.face_angles.min()) > 5.0  # no degenerate or sliver face


@pytest.mark.parametrize(("make", "kwargs"), CASES, ids=CASE_IDS)
def test_no_self_contact(make, kwargs):
    # Vertices far apart on the surface (in the chart) must not come close in space.
    shape = make(**kwargs)
    chart = _chart_points(shape)
    pairs = cKDTree(shape.vertices).query_pairs(0.1, output_type="ndarray")
    far = np.linalg.norm(chart[pairs[:, 0]] - chart[pairs[:, 1]], axis=1) > 0.5
    assert not far.any()


def test_vertex_count_range():
    small = tube(n_along=12, n_around=14)
    large = tube(n_along=200, n_around=80)
    assert 150 <= small.n_vertices <= 250
    assert 18_000 <= large.n_vertices <= 22_000
    assert [figure(resolution=r).n_vertices for r in (1, 2, 3, 4)] == [448, 832, 1274, 1844]


@pytest.mark.parametrize(
    ("first", "second"),
    [
        (lambda: tube(bend=0.0), lambda: tube(bend=np.pi / 2)),
        (lambda: figure(resolution=2, pose="rest"), lambda: figure(resolution=2, pose="bent")),
        (lambda: figure(resolution=2, pose="curled"), lambda: figure(resolution=2, pose=-0.5)),
    ],
    ids=["tube", "figure-rest-bent", "figure-curled-float"],
)
def test_poses_share_connectivity_and_chart(first, second):
    a, b = first(), second()
    np.testing.assert_array_equal(a.faces, b.faces)
    np.testing.assert_array_equal(a.params, b.params)
    assert not np.allclose(a.vertices, b.vertices)  # the pose did change the geometry
    np.testing.assert_array_equal(ground_truth(a, b), np.arange(a.n_vertices))


def test_deterministic_and_seeded():
    np.testing.assert_array_equal(figure(random_state=3).vertices, figure(random_state=3).vertices)
    assert not np.array_equal(figure(random_state=3).params, figure(random_state=4).params)
    # the seed only jitters the vertices within the chart: same counts, moved vertices
    jittered, regular = tube(random_state=1), tube(random_state=None)
    assert jittered.faces.shape == regular.faces.shape
    assert jittered.n_vertices == regular.n_vertices


def test_arrays_are_read_only():
    shape = tube()
    with pytest.raises(ValueError):
        shape.vertices[0, 0] = 1.0


@pytest.mark.parametrize(
    "shape", [tube(), figure(resolution=2, pose="bent")], ids=["tube", "figure"]
)
def test_ground_truth_to_itself_is_identity(shape):
    truth = ground_truth(shape, shape)
    assert truth.dtype == np.int64
    np.testing.assert_array_equal(truth, np.arange(shape.n_vertices))
    # the nearest-neighbour path (no shortcut) agrees: a copy with perturbed params order
    copy, perm = rigid_copy(shape, random_state=5)
    np.testing.assert_array_equal(ground_truth(shape, copy), perm)


@pytest.mark.parametrize(
    ("source", "target"),
    [
        (tube(n_along=40, n_around=16), tube(n_along=25, n_around=12, random_state=3)),
        (tube(n_along=25, n_around=12, random_state=3), tube(n_along=40, n_around=16)),
        (figure(resolution=2), figure(resolution=3, random_state=1)),
        (figure(resolution=3), figure(resolution=1)),
    ],
    ids=["tube-fine-coarse", "tube-coarse-fine", "figure-2-3", "figure-3-1"],
)
def test_ground_truth_across_resolutions_is_close_in_space(source, target):
    truth = ground_truth(source, target)
    assert source.n_vertices != target.n_vertices
    mean_edge = _mesh(target).edges_unique_length.mean()
    distance = np.linalg.norm(source.vertices - target.vertices[truth], axis=1)
    assert distance.max() < 1.5 * mean_edge
    assert distance.mean() < 0.5 * mean_edge


def test_ground_truth_handles_periodic_theta():
    # a point at theta = 2 pi - 0.001 must match the vertex at theta = 0 of its ring
    shape = tube(random_state=None)
    at_zero = np.flatnonzero((shape.params[:, 1] == 0.0) & (shape.params[:, 0] > 1.0))[0]
    t_ring = shape.params[at_zero, 0]
    t_min, t_max = shape.params[:, 0].min(), shape.params[:, 0].max()
    probe = SyntheticShape(
        vertices=np.zeros((3, 3)),
        faces=np.zeros((0, 3)),
        params=[[t_ring, 2 * np.pi - 1e-3], [t_min, 0.0], [t_max, 0.0]],
        name="probe",
    )
    assert ground_truth(probe, shape)[0] == at_zero


def test_rigid_copy_truth():
    shape = figure(resolution=2, pose="bent")
    angle = 0.7
    c, s = np.cos(angle), np.sin(angle)
    rotation = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    copy, truth = rigid_copy(shape, rotation=rotation, translation=[1.0, -2.0, 3.0], scale=2.5)
    expected = 2.5 * shape.vertices @ rotation.T + np.array([1.0, -2.0, 3.0])
    np.testing.assert_allclose(copy.vertices[truth], expected, rtol=0, atol=1e-12)
    np.testing.assert_array_equal(copy.faces, truth[shape.faces])
    np.testing.assert_array_equal(copy.params[truth], shape.params)
    np.testing.assert_array_equal(np.sort(truth), np.arange(shape.n_vertices))
    assert not np.array_equal(truth, np.arange(shape.n_vertices))
    np.testing.assert_allclose(_mesh(copy).volume, 2.5**3 * _mesh(shape).volume, rtol=1e-10)


def test_rigid_copy_random_defaults_are_seeded():
    shape = tube(n_along=12, n_around=14)
    copy_a, truth_a = rigid_copy(shape, random_state=7)
    copy_b, truth_b = rigid_copy(shape, random_state=7)
    np.testing.assert_array_equal(truth_a, truth_b)
    np.testing.assert_array_equal(copy_a.vertices, copy_b.vertices)
    # the random motion is rigid: pairwise distances are kept
    pairs = np.array([[0, 5], [3, 100], [17, 150]])
    np.testing.assert_allclose(
        _edge_lengths(copy_a, truth_a[pairs]), _edge_lengths(shape, pairs), rtol=1e-12
    )
    same, identity = rigid_copy(shape, permute=False)
    np.testing.assert_array_equal(identity, np.arange(shape.n_vertices))
    np.testing.assert_array_equal(same.faces, shape.faces)


def test_bending_is_near_isometric():
    straight, bent = tube(), tube(bend=np.pi / 2)
    edges = _mesh(straight).edges_unique
    before, after = _edge_lengths(straight, edges), _edge_lengths(bent, edges)
    change = np.abs(after - before) / before
    assert np.median(change) < 0.05
    # edges around the tube are carried rigidly; along it, stretch and squeeze cancel
    along = np.abs(np.diff(straight.params[edges, 0], axis=1)[:, 0]) > 0.05
    np.testing.assert_allclose(after[along].sum(), before[along].sum(), rtol=0.01)
    # Pappus: bending a tube along a circular arc keeps its volume
    plain = [tube(bumps=False, bend=b) for b in (0.0, np.pi / 2)]
    np.testing.assert_allclose(_mesh(plain[1]).volume, _mesh(plain[0]).volume, rtol=1e-3)


def test_figure_poses_move_only_the_joints():
    rest, bent = figure(resolution=2, pose="rest"), figure(resolution=2, pose="bent")
    edges = _mesh(rest).edges_unique
    before, after = _edge_lengths(rest, edges), _edge_lengths(bent, edges)
    change = np.abs(after - before) / before
    assert np.median(change) < 1e-9  # the parts between hinges move rigidly
    assert np.mean(change) < 0.08
    np.testing.assert_allclose(_mesh(bent).volume, _mesh(rest).volume, rtol=0.01)


def _radial_profile(shape: SyntheticShape, length: float) -> np.ndarray:
    """Distance of each vertex of a straight shape from its centre line (the x axis)."""
    x = np.clip(shape.vertices[:, 0], 0.0, length)
    return np.linalg.norm(shape.vertices - np.column_stack([x, 0 * x, 0 * x]), axis=1)


def _best_symmetry_mismatch(shape: SyntheticShape, length: float) -> float:
    """Smallest worst-case change of the radial profile under candidate chart symmetries.

    Candidates: end-to-end reversal, mirror theta -> c - theta and rotation
    theta -> theta + c (c on a 10-degree grid), and their combinations; pure
    rotations by less than 30 degrees are too close to the identity to count.
    """
    t_min, t_max = shape.params[:, 0].min(), shape.params[:, 0].max()
    rho = _radial_profile(shape, length)
    tree = cKDTree(_chart_points(shape))
    t, theta = shape.params.T
    worst = []
    for reverse in (False, True):
        for mirror in (False, True):
            for c in np.radians(np.arange(0, 360, 10)):
                if not (reverse or mirror) and min(c, 2 * np.pi - c) < np.radians(30):
                    continue
                mapped = np.column_stack([
                    t_min + t_max - t if reverse else t,
                    c - theta if mirror else theta + c,
                ])
                _, j = tree.query(capsule.chart_embedding(mapped, t_min, t_max))
                worst.append(np.abs(rho - rho[j]).max())
    return min(worst)


def test_bumped_shapes_have_no_symmetry():
    plain = tube(bumps=False, random_state=None)
    assert _best_symmetry_mismatch(plain, 4.0) < 1e-12  # control: a plain capsule is symmetric
    assert _best_symmetry_mismatch(tube(random_state=None), 4.0) > 0.1 * 0.5
    assert _best_symmetry_mismatch(figure(resolution=2, random_state=None), 7.0) > 0.1 * 0.45


def test_ends_differ():
    def end_profiles(shape):
        ends = [np.argmin(shape.params[:, 0]), np.argmax(shape.params[:, 0])]
        return [np.sort(np.linalg.norm(shape.vertices - shape.vertices[e], axis=1)) for e in ends]

    start, end = end_profiles(tube(bumps=False, random_state=None))
    np.testing.assert_allclose(start, end, rtol=0, atol=1e-12)
    start, end = end_profiles(tube(random_state=None))
    assert np.abs(start - end).max() > 0.02
    start, end = end_profiles(figure(random_state=None))
    assert np.abs(start - end).mean() > 0.1


def test_sphere():
    vertices, faces = sphere(subdivisions=3, radius=2.0)
    assert vertices.shape == (642, 3) and faces.dtype == np.int64
    np.testing.assert_allclose(np.linalg.norm(vertices, axis=1), 2.0, rtol=1e-14)
    mesh = trimesh.Trimesh(vertices, faces, process=False)
    assert mesh.is_watertight and mesh.is_winding_consistent and mesh.volume > 0


def test_save_example_pair(tmp_path):
    source_path, target_path, truth_path = datasets.save_example_pair(tmp_path / "ex")
    assert [p.name for p in (source_path, target_path, truth_path)] == [
        "creature_rest.off", "creature_bent.off", "creature_rest_to_bent.gt.txt",
    ]
    source = creature(resolution=1, pose="rest")
    target = creature(resolution=2, pose="bent", random_state=1)
    for shape, path in ((source, source_path), (target, target_path)):
        loaded = trimesh.load(path, process=False)
        np.testing.assert_allclose(loaded.vertices, shape.vertices, rtol=0, atol=1e-8)
        np.testing.assert_array_equal(loaded.faces, shape.faces)
    truth = np.loadtxt(truth_path, dtype=np.int64)
    np.testing.assert_array_equal(truth, ground_truth(source, target))
    total = sum(p.stat().st_size for p in (source_path, target_path, truth_path))
    assert total < 300_000


def test_bundled_examples():
    # the files in examples/ are what save_example_pair writes (checked loosely: they
    # are regenerated on one machine, and tessellations may differ in the last bits)
    directory = Path(__file__).resolve().parents[2] / "examples"
    names = ["creature_rest.off", "creature_bent.off", "creature_rest_to_bent.gt.txt"]
    assert sorted(p.name for p in directory.iterdir()) == sorted(names)
    assert sum((directory / name).stat().st_size for name in names) < 300_000
    source = trimesh.load(directory / names[0], process=False)
    target = trimesh.load(directory / names[1], process=False)
    truth = np.loadtxt(directory / names[2], dtype=np.int64)
    assert (len(source.vertices), len(target.vertices)) == (500, 1000)
    assert source.is_watertight and target.is_watertight
    assert truth.shape == (500,) and truth.min() >= 0 and truth.max() < 1000


@pytest.mark.parametrize(
    ("call", "match"),
    [
        (lambda: tube(n_along=1), "'n_along' parameter of tube must be an int >= 2"),
        (lambda: tube(n_along=10.0), "'n_along' parameter of tube"),
        (lambda: tube(n_around=2), "'n_around' parameter of tube must be an int >= 3"),
        (lambda: tube(length=0.0), "'length' parameter of tube must be a finite float > 0"),
        (lambda: tube(radius=np.nan), "'radius' parameter of tube"),
        (lambda: tube(bend=4.0), "'bend' parameter of tube"),
        (lambda: tube(length=1.0, bend=1.5), "'bend' parameter of tube"),
        (lambda: tube(bumps=1), "'bumps' parameter of tube must be a bool"),
        (lambda: tube(random_state=-1), "'random_state' parameter of tube"),
        (lambda: tube(random_state=1.5), "'random_state' parameter of tube"),
        (lambda: figure(resolution=0), "'resolution' parameter of figure must be an int >= 1"),
        (lambda: figure(pose="dancing"), "'pose' parameter of figure must be one of"),
        (lambda: figure(pose=1.5), "'pose' parameter of figure"),
        (lambda: figure(pose=True), "'pose' parameter of figure"),
        (lambda: figure(random_state="0"), "'random_state' parameter of figure"),
        (lambda: creature(resolution=0), r"'resolution' parameter of creature .* \[1, 6\]"),
        (lambda: creature(resolution=7), "'resolution' parameter of creature"),
        (lambda: creature(resolution=1.0), "'resolution' parameter of creature"),
        (lambda: creature(pose="dancing"), "'pose' parameter of creature must be one of"),
        (lambda: creature(pose=-1.5), "'pose' parameter of creature"),
        (lambda: creature(pose=np.nan), "'pose' parameter of creature"),
        (lambda: creature(pose=True), "'pose' parameter of creature"),
        (lambda: creature(random_state=-1), "'random_state' parameter of creature"),
        (lambda: sphere(subdivisions=8), r"'subdivisions' parameter of sphere must be .* \[0, 7\]"),
        (lambda: sphere(radius=-1.0), "'radius' parameter of sphere"),
        (lambda: ground_truth(tube(), tube(length=5.0)), "one family"),
        (lambda: ground_truth(tube(), figure()), "one family"),
        (lambda: ground_truth(creature(), figure()), "one family"),
        (lambda: ground_truth(tube(), creature()), "one family"),
        (lambda: ground_truth(np.zeros((3, 3)), tube()), "'source' parameter of ground_truth"),
        (lambda: rigid_copy(tube(), rotation=np.diag([1.0, 1.0, -1.0])), "'rotation' parameter"),
        (lambda: rigid_copy(tube(), rotation=2 * np.eye(3)), "'rotation' parameter"),
        (lambda: rigid_copy(tube(), translation=[1.0, 2.0]), "'translation' parameter"),
        (lambda: rigid_copy(tube(), scale=-1.0), "'scale' parameter of rigid_copy"),
        (lambda: rigid_copy(tube(), permute="yes"), "'permute' parameter of rigid_copy"),
        (lambda: rigid_copy(tube(), random_state=-3), "'random_state' parameter of rigid_copy"),
    ],
)
def test_invalid_parameters_raise(call, match):
    with pytest.raises(ParameterError, match=match):
        call()


# --------------------------------------------------------------------------
# creature
# --------------------------------------------------------------------------

CREATURES = {
    "r1-rest": dict(resolution=1),
    "r1-curled": dict(resolution=1, pose="curled", random_state=1),
    "r2-bent": dict(resolution=2, pose="bent", random_state=1),
    "r1-none-reverse": dict(resolution=1, pose=-1.0, random_state=None),
}
POSES = ["bent", "curled", -1.0, 0.5]


def _limb_labels(shape: SyntheticShape) -> np.ndarray:
    return creature_module._creature_labels(creature_module.creature_directions(shape.params))


@pytest.mark.parametrize("kwargs", CREATURES.values(), ids=CREATURES.keys())
def test_creature_closed_oriented_manifold(kwargs):
    shape = creature(**kwargs)
    mesh = _mesh(shape)
    assert shape.chart == "creature" and shape.params.shape == (shape.n_vertices, 2)
    assert shape.vertices.dtype == np.float64 and shape.faces.dtype == np.int64
    assert mesh.is_watertight and mesh.is_winding_consistent
    assert mesh.volume > 0  # outward normals
    assert mesh.body_count == 1 and mesh.euler_number == 2  # one sphere-like component
    assert len(np.unique(shape.faces.ravel())) == shape.n_vertices
    assert len(np.unique(np.sort(shape.faces, axis=1), axis=0)) == len(shape.faces)
    assert np.degrees(mesh.face_angles.min()) > 10.0  # no sliver; near-equilateral
    edges = mesh.edges_unique_length
    assert edges.max() < 3.0 * edges.mean()


def test_creature_vertex_counts_and_limbs():
    assert [creature(resolution=r).n_vertices for r in (1, 2)] == [500, 1000]
    mean_edges = [_mesh(creature(resolution=r)).edges_unique_length.mean() for r in (1, 2)]
    assert 0.15 < mean_edges[0] < 0.25
    np.testing.assert_allclose(mean_edges[0] / mean_edges[1], np.sqrt(2), rtol=0.1)
    # five limbs of clearly different lengths: the farthest vertex of each from the centre
    shape = creature(resolution=2)
    labels = _limb_labels(shape)
    reach = [np.linalg.norm(shape.vertices[labels == k], axis=1).max() for k in range(5)]
    np.testing.assert_allclose(reach, 0.7 + np.array([3.0, 2.0, 1.4, 1.0, 0.7]), atol=0.05)
    assert set(np.unique(labels)) == {-1, 0, 1, 2, 3, 4}


@pytest.mark.parametrize("pose", ["rest", *POSES])
def test_creature_limbs_never_touch(pose):
    rest = creature(resolution=2)
    shape = creature(resolution=2, pose=pose)
    labels = _limb_labels(shape)
    # different limbs stay apart
    for k in range(5):
        tree = cKDTree(shape.vertices[labels == k])
        for j in range(k):
            assert tree.query(shape.vertices[labels == j])[0].min() > 0.15
    # vertices close in space were close in the rest pose: no new contact
    pairs = cKDTree(shape.vertices).query_pairs(0.25, output_type="ndarray")
    assert np.linalg.norm(rest.vertices[pairs[:, 0]] - rest.vertices[pairs[:, 1]], axis=1).max() < 0.6


def test_creature_poses_share_connectivity_and_chart():
    rest = creature(resolution=1)
    for pose in POSES:
        posed = creature(resolution=1, pose=pose)
        np.testing.assert_array_equal(posed.faces, rest.faces)
        np.testing.assert_array_equal(posed.params, rest.params)
        assert not np.allclose(posed.vertices, rest.vertices)
        np.testing.assert_array_equal(ground_truth(rest, posed), np.arange(rest.n_vertices))
    np.testing.assert_array_equal(creature(pose=0.0).vertices, rest.vertices)
    np.testing.assert_array_equal(creature(pose=1.0).vertices, creature(pose="bent").vertices)
    # the body stays put; only limb vertices move
    moved = np.linalg.norm(creature(pose="curled").vertices - rest.vertices, axis=1) > 0
    assert np.all(_limb_labels(rest)[moved] >= 0)


def test_creature_poses_are_near_isometric():
    rest = creature(resolution=2)
    edges = _mesh(rest).edges_unique
    before = _edge_lengths(rest, edges)
    for pose in POSES:
        posed = creature(resolution=2, pose=pose)
        change = np.abs(_edge_lengths(posed, edges) - before) / before
        assert np.median(change) < 0.02  # in fact 0: the parts between hinges move rigidly
        assert np.mean(change) < 0.05
        np.testing.assert_allclose(_mesh(posed).volume, _mesh(rest).volume, rtol=0.01)


def test_creature_deterministic_and_seeded():
    a = creature(random_state=1)
    params, faces, _ = creature_module._creature_mesh.__wrapped__(1, 1)  # rebuilt, not cached
    np.testing.assert_array_equal(params, a.params)
    np.testing.assert_array_equal(faces, a.faces)
    other, regular = creature(random_state=0), creature(random_state=None)
    for shape in (other, regular):
        assert shape.n_vertices == a.n_vertices and not np.array_equal(shape.params, a.params)
    with pytest.raises(ValueError):
        a.vertices[0, 0] = 1.0


def test_creature_ground_truth_identity_and_rigid_copy():
    shape = creature(resolution=1, pose="bent")
    np.testing.assert_array_equal(ground_truth(shape, shape), np.arange(shape.n_vertices))
    copy, perm = rigid_copy(shape, scale=2.5, random_state=5)
    assert copy.chart == "creature"
    assert not np.array_equal(perm, np.arange(shape.n_vertices))
    np.testing.assert_array_equal(ground_truth(shape, copy), perm)  # the nearest-neighbour path
    np.testing.assert_array_equal(ground_truth(copy, shape), np.argsort(perm))


@pytest.mark.parametrize(
    ("source", "target"),
    [
        (dict(resolution=1), dict(resolution=2, random_state=1)),
        (dict(resolution=2, random_state=1), dict(resolution=1)),
        (dict(resolution=1), dict(resolution=1, random_state=None)),
    ],
    ids=["r1-r2", "r2-r1", "seed0-none"],
)
def test_creature_ground_truth_across_resolutions(source, target):
    a, b = creature(**source), creature(**target)
    truth = ground_truth(a, b)
    mean_edge = _mesh(b).edges_unique_length.mean()
    distance = np.linalg.norm(a.vertices - b.vertices[truth], axis=1)
    assert distance.max() < 1.5 * mean_edge
    assert distance.mean() < 0.5 * mean_edge
    # the truth does not depend on the poses, and is found on the same limb
    bent = creature(**{**target, "pose": "curled"})
    np.testing.assert_array_equal(ground_truth(creature(**source, pose="bent"), bent), truth)
    beyond_fillets = np.linalg.norm(creature_module.creature_rest(
        creature_module.creature_directions(a.params)), axis=1) > 1.2
    np.testing.assert_array_equal(_limb_labels(b)[truth][beyond_fillets],
                                  _limb_labels(a)[beyond_fillets])


def test_creature_ground_truth_tip_to_tip():
    # the chart shrinks exponentially along a limb; the truth must still be local there
    a, b = creature(resolution=1), creature(resolution=2, random_state=1)
    tips = [np.argmax(shape.vertices @ creature_module._CREATURE[0].frame[0]) for shape in (a, b)]
    truth = ground_truth(a, b)
    tip_edge = np.linalg.norm(b.vertices[truth[tips[0]]] - b.vertices[tips[1]])
    assert tip_edge < 0.2


@pytest.mark.parametrize("pose", ["rest", "curled"])
def test_creature_spectrum_is_well_separated(pose):
    # the geodesic Gaussian affinity (sigma = largest geodesic) of meshcorr.spectral.embedding has
    # distinct top eigenvalues, unlike the tube-like figure(): its eigenvectors do not mix
    from meshcorr.spectral.embedding import gaussian_affinity, top_eigenpairs
    from meshcorr.core.mesh import as_mesh

    shape = creature(resolution=1, pose=pose)
    distances = as_mesh((shape.vertices, shape.faces)).geodesic_matrix("heat")
    values, _ = top_eigenpairs(gaussian_affinity(distances), 7)
    gaps = values[1:6] / values[2:7] - 1.0
    assert np.all(gaps > 0.2)


def test_synthetic_shape_chart_is_checked():
    with pytest.raises(MeshError, match="chart"):
        SyntheticShape(np.zeros((3, 3)), [[0, 1, 2]], np.zeros((3, 2)), "x", chart="torus")
