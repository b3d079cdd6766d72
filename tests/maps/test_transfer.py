"""meshcorr.maps.transfer: checking a vertex map, pulling target values back, writing them."""

import numpy as np
import pytest

from meshcorr.errors import ParameterError
from meshcorr.maps.transfer import check_map, pull_back, transfer_attribute, write_values
from meshcorr.maps.colors import UNMAPPED_COLOR


def test_check_map_accepts_unmapped_and_returns_int64():
    mapping = check_map(np.array([2, -1, 0], dtype=np.int32), 3, 3)
    assert mapping.dtype == np.int64 and mapping.tolist() == [2, -1, 0]


@pytest.mark.parametrize("mapping, message", [
    (np.array([0.0, 1.0, 2.0]), r"^map must be a 1-D array of integer vertex indices"),
    (np.zeros((3, 1), dtype=int), r"Got shape \(3, 1\)"),
    (np.array([0, 1]), r"^map has 2 entries but the source mesh has 3 vertices"),
    (np.array([0, 1, 3]), r"^map entry 2 is 3, outside the target's vertex range 0\.\.2"),
    (np.array([0, -2, 1]), r"^map entry 1 is -2"),
])
def test_check_map_refusals(mapping, message):
    with pytest.raises(ParameterError, match=message):
        check_map(mapping, 3, 3)


def test_check_map_names_the_map():
    with pytest.raises(ParameterError, match=r"^map\.txt has 1 entries"):
        check_map(np.array([0]), 3, 3, name="map.txt")


def test_pull_back_composes_and_fills():
    values = np.array([10, 20, 30])
    np.testing.assert_array_equal(pull_back(values, np.array([2, 2, 0, 1])), [30, 30, 10, 20])
    pulled = pull_back(values, np.array([1, -1]))
    assert pulled.dtype.kind == "f" and pulled[0] == 20 and np.isnan(pulled[1])  # promoted for NaN
    rows = np.array([[1, 2, 3], [4, 5, 6]], dtype=np.uint8)
    pulled = pull_back(rows, np.array([-1, 1]), fill=np.array([0, 0, 0], dtype=np.uint8))
    np.testing.assert_array_equal(pulled, [[0, 0, 0], [4, 5, 6]])
    assert pulled.dtype == np.uint8


def test_transfer_attribute_shares_the_target_scale():
    values = np.array([0.0, 1.0, 2.0])
    colors, pulled = transfer_attribute(values, np.array([1, 1, -1]))
    np.testing.assert_array_equal(pulled[:2], [1.0, 1.0])
    assert np.isnan(pulled[2])
    # 1.0 is the middle of the target's range [0, 2], not an end of the pulled values' range
    middle, = np.unique(colors[:2], axis=0)
    assert not np.array_equal(middle, colors[2])
    np.testing.assert_array_equal(colors[2], UNMAPPED_COLOR)
    rgb = np.array([[255, 0, 0], [0, 255, 0]], dtype=np.uint8)
    colors, pulled = transfer_attribute(rgb, np.array([1, -1]))
    np.testing.assert_array_equal(colors, [[0, 255, 0], UNMAPPED_COLOR])


def test_write_values_text_and_npy(tmp_path):
    write_values(tmp_path / "map.txt", np.array([3, -1, 0]))
    assert (tmp_path / "map.txt").read_text().split() == ["3", "-1", "0"]
    write_values(tmp_path / "field.txt", np.array([0.5, 1 / 3]))
    np.testing.assert_allclose(np.loadtxt(tmp_path / "field.txt"), [0.5, 1 / 3], rtol=1e-9)
    write_values(tmp_path / "field.npy", np.array([1.5, 2.5]))
    np.testing.assert_array_equal(np.load(tmp_path / "field.npy"), [1.5, 2.5])
    assert sorted(p.name for p in tmp_path.iterdir()) == ["field.npy", "field.txt", "map.txt"]
