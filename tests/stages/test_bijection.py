"""One-to-one maps: :func:`meshcorr.stages.bijection.nearest_bijection` and ``bijective=True`` end to end."""

import itertools

import numpy as np
import pytest
import trimesh

import meshcorr
from meshcorr import datasets
from meshcorr.stages.bijection import nearest_bijection
from meshcorr.cli import main
from meshcorr.errors import ParameterError


def _cost(points: np.ndarray, mapping: np.ndarray, permutation: np.ndarray) -> float:
    return float(((points[mapping] - points[permutation]) ** 2).sum())


def test_a_permutation_comes_back_unchanged_as_a_copy():
    rng = np.random.default_rng(0)
    points, mapping = rng.normal(size=(30, 3)), rng.permutation(30)
    result = nearest_bijection(mapping, points)
    assert np.array_equal(result, mapping) and result is not mapping


def test_the_nearest_permutation_agrees_with_brute_force():
    rng = np.random.default_rng(1)
    for _ in range(5):
        points = rng.normal(size=(6, 3))
        mapping = rng.integers(0, 6, size=6)  # duplicates and unused vertices
        result = nearest_bijection(mapping, points)
        assert sorted(result) == list(range(6))
        best = min(_cost(points, mapping, np.array(p)) for p in itertools.permutations(range(6)))
        assert _cost(points, mapping, result) == pytest.approx(best, abs=1e-12)


def test_fixed_pairs_hold_even_where_the_map_disagrees():
    rng = np.random.default_rng(2)
    points = rng.normal(size=(40, 3))
    mapping = rng.permutation(40)
    mapping[5] = mapping[6]  # a duplicate
    fixed = np.array([[0, int(mapping[1])], [7, 3]])  # vertex 0 sent where vertex 1 goes
    result = nearest_bijection(mapping, points, fixed=fixed)
    assert sorted(result) == list(range(40))
    assert result[0] == mapping[1] and result[7] == 3


@pytest.mark.parametrize("fixed, message", [
    (np.array([[0, 1], [2, 1]]), "target vertex 1 is in 2 landmark pairs"),
    (np.array([[4, 1], [4, 2]]), "source vertex 4 is in 2 landmark pairs"),
])
def test_fixed_pairs_that_no_permutation_holds_are_refused(fixed, message):
    with pytest.raises(ParameterError, match=message):
        nearest_bijection(np.arange(10), np.zeros((10, 3)), fixed=fixed)


def test_unequal_counts_are_refused():
    with pytest.raises(ParameterError, match="as many target vertices as source vertices"):
        nearest_bijection(np.arange(10), np.zeros((11, 3)))


@pytest.fixture(scope="module")
def creature_and_rigid_copy():
    """A creature and a rotated, scaled, re-indexed copy; truth[i] is the copy's vertex of vertex i."""
    shape = datasets.creature(resolution=1)
    copy, truth = datasets.rigid_copy(shape, random_state=3)
    return shape, copy, np.asarray(truth)


@pytest.mark.parametrize("refine", [True, False])
def test_bijective_maps_with_landmarks_are_permutations_that_hold_them(creature_and_rigid_copy, refine):
    # One landmark is off by one edge, as a user's often are: pinned into a one-to-one map, it
    # repeats the image of the vertex that truly goes there.
    shape, copy, truth = creature_and_rigid_copy
    ring = np.unique(copy.faces[np.any(copy.faces == truth[200], axis=1)])
    neighbour = int(ring[ring != truth[200]][0])
    picks = np.array([3, 90, 200, 333])
    landmarks = np.stack([picks, [truth[3], truth[90], neighbour, truth[333]]], axis=1)
    result = meshcorr.match(shape, copy, bijective=True, refine=refine, landmarks=landmarks)
    assert sorted(result.map) == list(range(copy.n_vertices))
    assert np.array_equal(result.map[picks], landmarks[:, 1])
    assert np.mean(result.map == truth) > 0.9


def test_bijective_landmarks_sharing_a_target_are_refused_by_the_cli(creature_and_rigid_copy, tmp_path, capsys):
    shape, copy, truth = creature_and_rigid_copy
    paths = []
    for name, s in (("a.off", shape), ("b.off", copy)):
        trimesh.Trimesh(np.asarray(s.vertices), np.asarray(s.faces), process=False).export(tmp_path / name)
        paths.append(str(tmp_path / name))
    (tmp_path / "pairs.txt").write_text(f"3 {truth[3]}\n90 {truth[3]}\n")
    out = tmp_path / "map.txt"
    assert main(["match", *paths, "-o", str(out), "--bijective", "--landmarks", str(tmp_path / "pairs.txt"),
                 "-q"]) == 2
    err = capsys.readouterr().err
    assert f"target vertex {truth[3]} is in 2 landmark pairs" in err and "Traceback" not in err
    assert not out.exists()
