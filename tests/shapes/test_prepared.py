"""PreparedShape / prepare: the same maps as from the meshes, a versioned file, refusals (issue 13)."""

from __future__ import annotations

import json
import pickle
import zipfile

import numpy as np
import pytest

import meshcorr
from meshcorr import datasets as ds
from meshcorr.cli import main
from meshcorr.errors import ParameterError, PreparedShapeError
from meshcorr.pipeline.prepare import prepare
from meshcorr.pipeline.settings import SHAPE_SETTINGS
from meshcorr.shapes.prepared import FORMAT_VERSION, PreparedShape, mesh_digest


@pytest.fixture(scope="module")
def creature_poses():
    a, b = ds.creature(resolution=1), ds.creature(resolution=1, pose="bent")
    return (a.vertices, a.faces), (b.vertices, b.faces)


@pytest.mark.parametrize("mode", ["dense", "scalable"])
def test_prepared_shapes_give_the_map_of_the_meshes_bit_for_bit(creature_poses, mode, tmp_path):
    direct = meshcorr.match(*creature_poses, mode=mode)
    shapes = [prepare(mesh, mode=mode) for mesh in creature_poses]
    from_prepared = meshcorr.match(*shapes, mode=mode)
    np.testing.assert_array_equal(from_prepared.map, direct.map)
    np.testing.assert_array_equal(from_prepared.source_embedding, direct.source_embedding)
    # The per-shape stages are skipped.
    assert "geodesics" not in from_prepared.timings and "embedding" not in from_prepared.timings
    for name, shape in zip("ab", shapes):
        shape.save(tmp_path / f"{name}.npz")
    loaded = [PreparedShape.load(tmp_path / f"{name}.npz", mesh=mesh) for name, mesh in zip("ab", creature_poses)]
    np.testing.assert_array_equal(meshcorr.match(*loaded, mode=mode).map, direct.map)
    # Reused in the same process (rows cached by the first match) and mixed with a mesh.
    np.testing.assert_array_equal(meshcorr.match(shapes[0], creature_poses[1], mode=mode).map, direct.map)


def test_pickled_shape_is_its_file(creature_poses):
    shape = prepare(creature_poses[0], mode="scalable")
    copy = pickle.loads(pickle.dumps(shape))
    assert copy.settings == shape.settings and copy.digest == shape.digest
    np.testing.assert_array_equal(copy.spectrum.embedding, shape.spectrum.embedding)
    assert not copy.spectrum.embedding.flags.writeable
    np.testing.assert_array_equal(meshcorr.match(copy, creature_poses[1], mode="scalable").map,
                                  meshcorr.match(shape, creature_poses[1], mode="scalable").map)


def test_file_header_is_documented_json(creature_poses, tmp_path):
    path = tmp_path / "a.npz"
    shape = prepare(creature_poses[0], k=5, random_state=3)
    shape.save(path)
    with np.load(path, allow_pickle=False) as data:
        header = json.loads(data["header"].tobytes().decode())
        assert data["spectrum.embedding"].shape == (shape.n_vertices, 4)
    assert header["format"] == FORMAT_VERSION and header["meshcorr"] == meshcorr.__version__
    assert header["mesh_sha256"] == mesh_digest(shape.mesh)
    assert header["settings"] == dict(shape.settings) and header["settings"]["k"] == 5
    assert header["settings"]["mode"] == "dense" and header["settings"]["random_state"] == 3
    assert "PreparedShape(" in repr(shape) and "n_vertices=500" in repr(shape)


def test_load_refuses_another_mesh_other_settings_and_other_versions(creature_poses, tmp_path):
    path = tmp_path / "a.npz"
    prepare(creature_poses[0]).save(path)
    with pytest.raises(PreparedShapeError, match="prepared for another mesh"):
        PreparedShape.load(path, mesh=creature_poses[1])
    with pytest.raises(PreparedShapeError, match=r"other settings: k=6 \(asked: 5\)"):
        PreparedShape.load(path, settings=dict(SHAPE_SETTINGS, k=5))
    with pytest.raises(PreparedShapeError, match=r"other settings: k=6 \(asked: 8\)"):  # some settings only
        PreparedShape.load(path, settings={"k": 8})
    assert PreparedShape.load(path, settings={"k": 6}).settings["k"] == 6
    # Another format version: rewrite the header.
    with np.load(path, allow_pickle=False) as data:
        arrays = {name: data[name] for name in data.files}
    header = json.loads(arrays["header"].tobytes().decode())
    header["meshcorr"] = "0.0.1"
    arrays["header"] = np.frombuffer(json.dumps(header).encode(), dtype=np.uint8)
    old = tmp_path / "old.npz"
    np.savez(old, **arrays)
    with pytest.raises(PreparedShapeError, match="written by meshcorr 0.0.1.*Prepare the mesh again"):
        PreparedShape.load(old)
    garbage = tmp_path / "garbage.npz"
    garbage.write_bytes(b"not a zip")
    with pytest.raises(PreparedShapeError, match="is not a prepared shape written by meshcorr") as refused:
        PreparedShape.load(garbage)
    assert "pickle" not in str(refused.value)  # numpy's advice to unpickle is not passed on
    with zipfile.ZipFile(tmp_path / "empty.npz", "w"):
        pass
    with pytest.raises(PreparedShapeError, match="is not a prepared shape"):
        PreparedShape.load(tmp_path / "empty.npz")
    with pytest.raises(PreparedShapeError, match="does not exist"):
        PreparedShape.load(tmp_path / "missing.npz")


def test_match_refuses_shapes_prepared_with_other_settings_or_mode(creature_poses):
    shape = prepare(creature_poses[0], random_state=1)
    with pytest.raises(PreparedShapeError, match=r"source .* random_state=1 \(asked: 0\)"):
        meshcorr.match(shape, creature_poses[1])
    with pytest.raises(PreparedShapeError, match=r"target .* random_state=1 \(asked: 0\)"):
        meshcorr.match(creature_poses[1], shape)
    with pytest.raises(PreparedShapeError, match=r"mode='dense' \(asked: 'scalable'\)"):
        meshcorr.match(prepare(creature_poses[0]), creature_poses[1], mode="scalable")
    # The sample count does not matter to the dense mode, and is refused in the scalable one.
    dense = prepare(creature_poses[0], n_samples=30)
    np.testing.assert_array_equal(meshcorr.match(dense, creature_poses[1]).map, meshcorr.match(*creature_poses).map)
    with pytest.raises(PreparedShapeError, match=r"n_samples=30 \(asked: 48\)"):
        meshcorr.match(prepare(creature_poses[0], mode="scalable", n_samples=30), creature_poses[1], mode="scalable")


def test_a_baseline_takes_the_mesh_of_a_prepared_shape(creature_poses):
    shape = prepare(creature_poses[0])
    np.testing.assert_array_equal(meshcorr.match(shape, creature_poses[1], method="icp").map,
                                  meshcorr.match(*creature_poses, method="icp").map)


@pytest.mark.parametrize("options, message", [
    ({"k": 1}, "'k' parameter must be an int >= 2"),
    ({"n_samples": 3}, "'n_samples' parameter must be an int >= 7"),
    ({"refine": "yes"}, "'refine' parameter must be True or False"),
    ({"largest_component": 1}, "'largest_component' parameter must be True or False"),
    ({"random_state": 1.5}, "'random_state' parameter must be an int"),
    ({"mode": "fast"}, "'mode' parameter must be one of"),
])
def test_prepare_checks_its_options(creature_poses, options, message):
    with pytest.raises(ParameterError, match=message):
        prepare(creature_poses[0], **options)


def test_n_landmarks_was_renamed_n_samples(creature_poses, tmp_path, capsys):
    with pytest.raises(ParameterError, match="Unknown setting 'n_landmarks' \\('n_landmarks' is now 'n_samples'\\)"):
        meshcorr.match(*creature_poses, n_landmarks=48)
    shape = ds.creature(resolution=1)
    import trimesh

    path = tmp_path / "a.off"
    trimesh.Trimesh(shape.vertices, shape.faces, process=False).export(path)
    code = main(["match", str(path), str(path), "-o", str(tmp_path / "m.txt"), "--landmarks", "48"])
    assert code == 2
    assert "--landmarks N was renamed --samples N" in capsys.readouterr().err
    code = main(["match", str(path), str(path), "-o", str(tmp_path / "m.txt"), "--landmarks",
                 str(tmp_path / "pairs.txt")])
    assert code == 3 and "No such landmark file" in capsys.readouterr().err


def test_prepared_shapes_with_user_landmarks_give_the_same_map(creature_poses):
    landmarks = [(0, 0), (250, 250)]
    shapes = [prepare(mesh) for mesh in creature_poses]
    np.testing.assert_array_equal(meshcorr.match(*shapes, landmarks=landmarks).map,
                                  meshcorr.match(*creature_poses, landmarks=landmarks).map)
    np.testing.assert_array_equal(meshcorr.match(*shapes, extremities=False).map,
                                  meshcorr.match(*creature_poses, extremities=False).map)


def test_prepared_shape_carries_the_per_pair_quantities_through_its_file(creature_poses, tmp_path):
    """What prepare computes for the pairs (curvature table, orientation regions, the distortion's source
    rows, the extremities) is there after save/load, and the loaded shape gives the same map."""
    from meshcorr.choice.extremities import spectrum_extremities
    from meshcorr.choice.selection import distortion_sources

    shapes = [prepare(mesh, mode="scalable") for mesh in creature_poses]
    for shape in shapes:
        kinds = {key[0] for key in shape.mesh.store}
        assert {"curvature_table", "orientation_regions"} <= kinds
        assert set(map(int, distortion_sources(shape.n_vertices, 0))) <= set(shape.spectrum.rows)
        assert ("extremities", 0) in shape.spectrum.memo and "spread" in shape.spectrum.memo
    direct = meshcorr.match(*creature_poses, mode="scalable")
    for name, shape in zip("ab", shapes):
        shape.save(tmp_path / f"{name}.npz")
    loaded = [PreparedShape.load(tmp_path / f"{name}.npz", mesh=mesh) for name, mesh in zip("ab", creature_poses)]
    for shape, original in zip(loaded, shapes):
        key = ("curvature_table", 0.045)
        np.testing.assert_array_equal(shape.mesh.store[key], original.mesh.store[key])
        assert set(original.spectrum.rows) <= set(shape.spectrum.rows)
        assert not shape.spectrum.memo  # recomputed on demand: the same tips
        tips, before = spectrum_extremities(shape.mesh, shape.spectrum), original.spectrum.memo[("extremities", 0)]
        np.testing.assert_array_equal(tips.vertices, before.vertices)
        np.testing.assert_array_equal(tips.distances, before.distances)
    np.testing.assert_array_equal(meshcorr.match(*loaded, mode="scalable").map, direct.map)
    # A stale file (made for the other mesh) is still refused before any of it is used.
    with pytest.raises(PreparedShapeError, match="another mesh"):
        PreparedShape.load(tmp_path / "a.npz", mesh=creature_poses[1])
