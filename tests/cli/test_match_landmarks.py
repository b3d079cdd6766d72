"""``meshcorr match --landmarks FILE`` and ``--landmarks-vts`` (issue 12)."""

import re

import numpy as np
import pytest
import trimesh

from meshcorr import datasets
from meshcorr.cli import main
from meshcorr.stages.landmarks import read_landmarks
from meshcorr.errors import InputError


@pytest.fixture(scope="module")
def meshes(tmp_path_factory):
    """A creature and a rotated, re-indexed copy; truth[i] is the copy's vertex of vertex i."""
    folder = tmp_path_factory.mktemp("landmarks")
    shape = datasets.creature(resolution=1)
    copy, truth = datasets.rigid_copy(shape, random_state=4)
    paths = []
    for name, s in (("a.off", shape), ("b.off", copy)):
        trimesh.Trimesh(np.asarray(s.vertices), np.asarray(s.faces), process=False).export(folder / name)
        paths.append(str(folder / name))
    return folder, paths, np.asarray(truth)


def test_landmark_file_pairs_are_mapped_exactly(meshes, tmp_path):
    folder, (a, b), truth = meshes
    picks = [3, 40, 200]
    # The third pair is deliberately off by one edge: the map must follow the user there.
    faces = trimesh.load(b, process=False).faces
    ring = np.unique(faces[np.any(faces == truth[200], axis=1)])
    neighbour = int(ring[ring != truth[200]][0])
    pairs = [(3, truth[3]), (40, truth[40]), (200, neighbour)]
    (tmp_path / "pairs.txt").write_text("# source target\n" + "".join(f"{i} {j}\n" for i, j in pairs))
    out = tmp_path / "map.txt"
    assert main(["match", a, b, "-o", str(out), "--landmarks", str(tmp_path / "pairs.txt"), "-q"]) == 0
    mapping = np.loadtxt(out, dtype=np.int64)
    assert [int(mapping[i]) for i in picks] == [int(j) for _, j in pairs]
    assert np.mean(mapping == truth) > 0.95


def test_landmarks_as_a_vts_pair(meshes, tmp_path):
    folder, (a, b), truth = meshes
    picks = np.array([5, 60, 300])
    (tmp_path / "a.vts").write_text("".join(f"{i + 1}\n" for i in picks))
    (tmp_path / "b.vts").write_text("".join(f"{truth[i] + 1}\n" for i in picks))
    out = tmp_path / "map.npy"
    assert main(["match", "--landmarks-vts", str(tmp_path / "a.vts"), str(tmp_path / "b.vts"), a, b,
                 "-o", str(out), "-q"]) == 0
    mapping = np.load(out)
    assert np.array_equal(mapping[picks], truth[picks])


def test_a_bad_landmark_line_names_the_file_and_line(meshes, tmp_path, capsys):
    folder, (a, b), _ = meshes
    (tmp_path / "pairs.txt").write_text("1 2\n3 x\n")
    assert main(["match", a, b, "-o", str(tmp_path / "m.txt"), "--landmarks", str(tmp_path / "pairs.txt")]) == 3
    err = capsys.readouterr().err
    assert "pairs.txt, line 2" in err and not (tmp_path / "m.txt").exists()


@pytest.mark.parametrize("text, message", [
    ("1 2\n# a comment\n3 99999\n", "pairs.txt, line 3: target vertex 99999 is outside the target mesh's "
                                    r"vertices 0\.\.499 \(0-based\)"),
    ("1 2\n-4 5\n", "pairs.txt, line 2: source vertex -4 is outside"),
    ("7 2\n7 2\n1 3\n7 4\n", "pairs.txt, line 4: source vertex 7 already has another target vertex "
                               "on line 1"),
])
def test_a_bad_landmark_pair_names_the_file_and_line(meshes, tmp_path, capsys, text, message):
    folder, (a, b), _ = meshes
    (tmp_path / "pairs.txt").write_text(text)
    code = main(["match", a, b, "-o", str(tmp_path / "m.txt"), "--landmarks", str(tmp_path / "pairs.txt")])
    err = capsys.readouterr().err
    assert code == 3 and re.search(message, err), err
    assert not (tmp_path / "m.txt").exists()


def test_a_bad_vts_landmark_is_named_as_written_in_its_file(meshes, tmp_path, capsys):
    folder, (a, b), _ = meshes
    (tmp_path / "a.vts").write_text("5\n6\n")
    (tmp_path / "b.vts").write_text("5\n501\n")  # the target has 500 vertices: 1..500 in a .vts
    code = main(["match", a, b, "-o", str(tmp_path / "m.txt"), "--landmarks-vts", str(tmp_path / "a.vts"),
                 str(tmp_path / "b.vts")])
    err = capsys.readouterr().err
    assert code == 3 and "b.vts, line 2: target vertex 501 is outside the target mesh's vertices 1..500 " \
        "(1-based, as in a .vts file)" in err, err


def test_a_vts_pair_given_twice_counts_once(meshes, tmp_path):
    # TOSCA's own .vts pairs list some points twice; the same pair twice is no contradiction.
    folder, (a, b), truth = meshes
    picks = np.array([5, 60, 5, 300])
    (tmp_path / "a.vts").write_text("".join(f"{i + 1}\n" for i in picks))
    (tmp_path / "b.vts").write_text("".join(f"{truth[i] + 1}\n" for i in picks))
    out = tmp_path / "map.npy"
    assert main(["match", "--landmarks-vts", str(tmp_path / "a.vts"), str(tmp_path / "b.vts"), a, b,
                 "-o", str(out), "-q"]) == 0
    assert np.array_equal(np.load(out)[picks], truth[picks])


@pytest.mark.parametrize("symmetry", ["cost", "mirror"])
def test_landmarks_refuse_a_symmetry_that_would_set_them_aside(meshes, tmp_path, capsys, symmetry):
    folder, (a, b), truth = meshes
    (tmp_path / "pairs.txt").write_text(f"3 {truth[3]}\n")
    code = main(["match", a, b, "-o", str(tmp_path / "m.txt"), "--landmarks", str(tmp_path / "pairs.txt"),
                 "--symmetry", symmetry])
    assert code == 2 and f"--symmetry {symmetry}" in capsys.readouterr().err


def test_landmarks_given_twice_is_a_usage_error(meshes, tmp_path, capsys):
    folder, (a, b), _ = meshes
    (tmp_path / "p.txt").write_text("1 2\n")
    code = main(["match", a, b, "-o", str(tmp_path / "m.txt"), "--landmarks", str(tmp_path / "p.txt"),
                 "--landmarks-vts", str(tmp_path / "p.txt"), str(tmp_path / "p.txt")])
    assert code == 2 and "Give the landmarks once" in capsys.readouterr().err


@pytest.mark.parametrize("text, message", [("", "holds no pairs"), ("1 2 3\n", "line 1"),
                                           ("\xff\xfe\n", "plain text")])
def test_read_landmarks_refuses_malformed_files(tmp_path, text, message):
    path = tmp_path / "p.txt"
    path.write_bytes(text.encode("latin-1"))
    with pytest.raises(InputError, match=message):
        read_landmarks(path)
