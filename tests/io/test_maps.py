"""meshcorr.io.maps: map files (text and .npy) round-trip, and their refusals."""

import os

import numpy as np
import pytest

from meshcorr.errors import ParameterError
from meshcorr.io import read_map, write_map


@pytest.mark.parametrize("name", ["map.txt", "map.map", "map", "map.npy"])
def test_map_round_trip(tmp_path, name):
    mapping = np.array([3, 0, 2, 2, 1, 123456789])
    path = tmp_path / name
    write_map(path, mapping)
    result = read_map(path)
    assert result.dtype == np.int64
    np.testing.assert_array_equal(result, mapping)
    assert sorted(os.listdir(tmp_path)) == [name]


def test_text_map_format(tmp_path):
    write_map(tmp_path / "m.txt", np.array([4, 0, 7], dtype=np.int32))
    assert (tmp_path / "m.txt").read_text() == "4\n0\n7\n"


def test_npy_map_format(tmp_path):
    write_map(tmp_path / "m.npy", [4, 0, 7])
    np.testing.assert_array_equal(np.load(tmp_path / "m.npy"), [4, 0, 7])


def test_read_map_missing(tmp_path):
    with pytest.raises(ParameterError, match="No such file"):
        read_map(tmp_path / "missing.txt")


def test_read_map_non_integer_text(tmp_path):
    path = tmp_path / "m.txt"
    path.write_text("1\n\n2.5\n3\n")
    with pytest.raises(ParameterError, match=r"line 3: expected one integer per line .*, got '2.5'"):
        read_map(path)


def test_read_map_non_integer_npy(tmp_path):
    path = tmp_path / "m.npy"
    np.save(path, np.array([0.5, 1.0]))
    with pytest.raises(ParameterError, match="1-D integer array"):
        read_map(path)


def test_read_map_corrupt_npy(tmp_path):
    path = tmp_path / "m.npy"
    path.write_bytes(b"not numpy")
    with pytest.raises(ParameterError, match="could not be read as a .npy array"):
        read_map(path)


def test_write_map_rejects_non_integer(tmp_path):
    with pytest.raises(ParameterError, match="1-D integer array"):
        write_map(tmp_path / "m.txt", np.array([[1, 2], [3, 4]]))
    with pytest.raises(ParameterError, match="1-D integer array"):
        write_map(tmp_path / "m.txt", np.array([1.5, 2.0]))
    assert os.listdir(tmp_path) == []


def test_a_uint64_entry_too_large_for_int64_is_refused_not_wrapped_to_unmapped(tmp_path):
    # 2**64 - 1 became -1, "unmapped" (issue 31, item 7)
    np.save(tmp_path / "small.npy", np.array([3, 0, 2], dtype=np.uint64))
    np.testing.assert_array_equal(read_map(tmp_path / "small.npy"), [3, 0, 2])
    np.save(tmp_path / "huge.npy", np.array([3, 2 ** 64 - 1, 2], dtype=np.uint64))
    with pytest.raises(ParameterError, match=r"huge.npy: entry 1 is 18446744073709551615, too large .* int64"):
        read_map(tmp_path / "huge.npy")


def test_an_unreadable_map_file_is_an_input_error(tmp_path, no_read_permission):
    # a PermissionError was an internal error of the command line, exit 1 (issue 31, item 13)
    write_map(tmp_path / "locked.txt", np.arange(3))
    no_read_permission("locked.txt")
    with pytest.raises(ParameterError, match=r"Cannot read the map file .*locked.txt \(MAP\): Permission denied"):
        read_map(tmp_path / "locked.txt", name="MAP")


def test_the_vectorised_writer_gives_the_text_of_one_formatted_integer_a_line(tmp_path):
    from meshcorr.io.maps import map_bytes, map_text

    rng = np.random.default_rng(0)
    for mapping in (rng.integers(-1, 10 ** 7, 5000), np.array([0, -1, 9, 10, 99, 100, 1000000]), np.array([-1, -1]),
                    np.array([0]), np.array([], dtype=np.int64)):
        expected = "".join(f"{value}\n" for value in mapping.tolist())  # the writer before issue 33
        assert map_bytes(mapping) == expected.encode("ascii") and map_text(mapping) == expected
        write_map(tmp_path / "m.txt", mapping)
        assert (tmp_path / "m.txt").read_text() == expected
        np.testing.assert_array_equal(read_map(tmp_path / "m.txt"), mapping) if len(mapping) else None
