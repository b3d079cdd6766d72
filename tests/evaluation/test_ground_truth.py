"""meshcorr.evaluation.ground_truth: the identity, .vts pairs and files of vertex pairs, with their refusals."""

import numpy as np
import pytest

from meshcorr.errors import InputError, ParameterError
from meshcorr.evaluation.ground_truth import GroundTruth, identity_truth, load_ground_truth, read_pairs, read_vts


def test_identity():
    truth = identity_truth(4, 4)
    assert len(truth) == 4 and truth.description == "identity"
    np.testing.assert_array_equal(truth.source, truth.target)
    with pytest.raises(InputError, match="needs meshes with equal vertex counts; the source has 4 and the target 5"):
        identity_truth(4, 5)
    assert load_ground_truth("identity", n_source=3, n_target=3).source.tolist() == [0, 1, 2]


def test_ground_truth_arrays_and_check():
    truth = GroundTruth([0, 2], [1, 1], "pairs.txt")
    with pytest.raises(ValueError):
        truth.source[0] = 5
    assert truth.check(3, 2) is truth
    with pytest.raises(InputError, match=r"pair 0 names target vertex 1, but the target mesh has 1 vertices .* "
                                         r"in pairs\.txt"):
        truth.check(3, 1)
    with pytest.raises(InputError, match="as many source as target vertices; got 2 and 1"):
        GroundTruth([0, 1], [0])


def test_vts_are_one_based(tmp_path):
    (tmp_path / "a.vts").write_text("1\n3\n2\n")
    (tmp_path / "b.vts").write_text("2\n2\n1\n")
    np.testing.assert_array_equal(read_vts(tmp_path / "a.vts"), [0, 2, 1])
    truth = load_ground_truth([tmp_path / "a.vts", tmp_path / "b.vts"], n_source=3, n_target=2)
    np.testing.assert_array_equal(truth.source, [0, 2, 1])
    np.testing.assert_array_equal(truth.target, [1, 1, 0])
    assert truth.description == "a.vts + b.vts"
    with pytest.raises(InputError, match=r"holds index 3 \(1-based\), but its mesh has 2 vertices"):
        read_vts(tmp_path / "a.vts", 2)
    (tmp_path / "zero.vts").write_text("0\n1\n")
    with pytest.raises(InputError, match="holds index 0, but .vts indices are 1-based"):
        read_vts(tmp_path / "zero.vts")
    (tmp_path / "text.vts").write_text("1\nx\n")
    with pytest.raises(InputError, match=r"text\.vts, line 2: a \.vts file holds one integer per line"):
        read_vts(tmp_path / "text.vts")


def test_pairs_and_dense_maps(tmp_path):
    (tmp_path / "pairs.txt").write_text("0 4\n2,1\n3:0\n")
    truth = read_pairs(tmp_path / "pairs.txt")
    assert truth.source.tolist() == [0, 2, 3] and truth.target.tolist() == [4, 1, 0]
    (tmp_path / "dense.txt").write_text("2\n-1\n0\n")
    truth = read_pairs(tmp_path / "dense.txt", n_source=3)
    assert truth.source.tolist() == [0, 2] and truth.target.tolist() == [2, 0]  # -1 skipped
    with pytest.raises(InputError, match="has 3 lines of one index each .* the source mesh has 4 vertices"):
        read_pairs(tmp_path / "dense.txt", n_source=4)
    (tmp_path / "mixed.txt").write_text("0 1\n2\n")
    with pytest.raises(InputError, match=r"line 2: mixes one- and two-column lines"):
        read_pairs(tmp_path / "mixed.txt")
    with pytest.raises(InputError, match="names target vertex 4, but the target mesh has 3 vertices"):
        load_ground_truth(tmp_path / "pairs.txt", n_source=4, n_target=3)


def test_load_refuses_a_lone_vts_and_odd_specs(tmp_path):
    (tmp_path / "a.vts").write_text("1\n")
    with pytest.raises(InputError, match="indexes one mesh only"):
        load_ground_truth(tmp_path / "a.vts", n_source=3, n_target=3)
    with pytest.raises(InputError, match="must both be .vts files"):
        load_ground_truth([tmp_path / "a.vts", tmp_path / "b.txt"], n_source=3, n_target=3)
    with pytest.raises(InputError, match="got 3 items"):
        load_ground_truth(["a", "b", "c"], n_source=3, n_target=3)


def write(path, lines):
    path.write_text("".join(f"{line}\n" for line in lines))
    return path


def test_vts_pair_is_one_based(tmp_path):
    a = write(tmp_path / "a.vts", [1, 3, 3, 5])
    b = write(tmp_path / "b.vts", [2, 2, 4, 1])
    truth = load_ground_truth([a, b], n_source=5, n_target=4)
    np.testing.assert_array_equal(truth.source, [0, 2, 2, 4])
    np.testing.assert_array_equal(truth.target, [1, 1, 3, 0])
    assert len(truth) == 4 and "a.vts" in truth.description


def test_vts_errors(tmp_path):
    a = write(tmp_path / "a.vts", [1, 2, 3])
    with pytest.raises(ParameterError, match="No such ground-truth file"):
        load_ground_truth([a, tmp_path / "missing.vts"], n_source=3, n_target=3)
    with pytest.raises(ParameterError, match="has 3 lines and .* has 2"):
        load_ground_truth([a, write(tmp_path / "b.vts", [1, 2])], n_source=3, n_target=3)
    with pytest.raises(ParameterError, match="1-based"):
        read_vts(write(tmp_path / "zero.vts", [0, 1, 2]))
    with pytest.raises(ParameterError, match="index 9 .* has 3 vertices"):
        read_vts(write(tmp_path / "big.vts", [1, 9]), n_vertices=3)
    with pytest.raises(ParameterError, match="line 2: a .vts file holds one integer"):
        read_vts(write(tmp_path / "text.vts", [1, "x y"]))
    with pytest.raises(ParameterError, match="is empty"):
        read_vts(write(tmp_path / "empty.vts", []))
    with pytest.raises(ParameterError, match="indexes one mesh only"):
        load_ground_truth(str(a), n_source=3, n_target=3)
    with pytest.raises(ParameterError, match="must both be .vts"):
        load_ground_truth([a, tmp_path / "b.txt"], n_source=3, n_target=3)


def test_pairs_file_and_dense_map(tmp_path):
    pairs = read_pairs(write(tmp_path / "p.txt", ["# comment", "0 4", "2,1", "3:0  # trailing"]))
    np.testing.assert_array_equal(pairs.source, [0, 2, 3])
    np.testing.assert_array_equal(pairs.target, [4, 1, 0])
    dense = load_ground_truth(write(tmp_path / "d.txt", [2, -1, 0]), n_source=3, n_target=3)
    np.testing.assert_array_equal(dense.source, [0, 2])
    np.testing.assert_array_equal(dense.target, [2, 0])
    with pytest.raises(ParameterError, match="line 2: mixes"):
        read_pairs(write(tmp_path / "mixed.txt", ["0 1", "2"]))
    with pytest.raises(ParameterError, match="line 1: expected a 0-based vertex pair"):
        read_pairs(write(tmp_path / "bad.txt", ["0 1 2"]))
    with pytest.raises(ParameterError, match="names target vertex 4, but the target mesh has 3"):
        load_ground_truth(tmp_path / "p.txt", n_source=5, n_target=3)
    with pytest.raises(ParameterError, match="names source vertex -2"):
        GroundTruth([-2], [0]).check(3, 3)


def test_identity_and_spec_errors():
    np.testing.assert_array_equal(load_ground_truth("identity", n_source=3, n_target=3).target, [0, 1, 2])
    with pytest.raises(ParameterError, match="equal vertex counts"):
        identity_truth(3, 4)
    with pytest.raises(ParameterError, match="got 3 items"):
        load_ground_truth(["a", "b", "c"], n_source=3, n_target=3)
    with pytest.raises(ParameterError, match="as many source as target"):
        GroundTruth([0, 1], [0])


def test_a_file_of_pairs_names_each_source_vertex_once(tmp_path):
    # a second target for a source vertex was taken: 501 points scored on a 500-vertex source (issue 31, item 7)
    with pytest.raises(InputError, match=r"two.txt, line 4: source vertex 0 already has the true target 4 on "
                                         r"line 1, and here 2; give each source vertex one true target"):
        read_pairs(write(tmp_path / "two.txt", ["0 4", "1 1", "# comment", "0 2"]))
    with pytest.raises(InputError, match=r"again.txt, line 3: the pair '1 1' is also on line 2; give each pair once"):
        read_pairs(write(tmp_path / "again.txt", ["0 4", "1 1", "1 1"]))
    assert len(read_pairs(write(tmp_path / "one.txt", ["0 4", "1 4"]))) == 2  # two sources on one target: fine
