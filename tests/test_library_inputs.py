"""Library input checks: dense-map truth files, .npz archives, precise_map's basis size, cache listings."""

import numpy as np
import pytest

from meshcorr.errors import InputError
from meshcorr.ground_truth import load_ground_truth, read_pairs


def _write_lines(path, values):
    path.write_text("".join(f"{value}\n" for value in values))
    return path


# ---------------------------------------------------------------- dense-map truth files

def test_dense_truth_with_too_few_lines_is_refused(tmp_path):
    short = _write_lines(tmp_path / "short.txt", range(10))  # was scored on its 10 lines
    with pytest.raises(InputError, match=r"short\.txt has 10 lines .* source mesh has 500 vertices") as error:
        load_ground_truth(short, n_source=500, n_target=500)
    assert "one line per source vertex" in str(error.value) and "'i j'" in str(error.value)
    with pytest.raises(InputError, match="has 10 lines"):
        read_pairs(short, n_source=500)


def test_dense_truth_with_too_many_lines_is_refused(tmp_path):
    long = _write_lines(tmp_path / "long.txt", [*range(10), -1, -1])  # trailing -1 lines were ignored
    with pytest.raises(InputError, match="has 12 lines .* has 10 vertices"):
        load_ground_truth(long, n_source=10, n_target=10)


def test_dense_truth_of_the_right_length_and_pair_files_still_load(tmp_path):
    dense = load_ground_truth(_write_lines(tmp_path / "d.txt", [2, -1, 0]), n_source=3, n_target=3)
    np.testing.assert_array_equal(dense.source, [0, 2])
    pairs = load_ground_truth(_write_lines(tmp_path / "p.txt", ["0 1"]), n_source=500, n_target=3)
    assert len(pairs) == 1  # a sparse file of pairs needs no line per vertex
    assert len(read_pairs(tmp_path / "d.txt")) == 2  # without a vertex count: unchecked, as before
