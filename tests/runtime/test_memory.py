"""meshcorr.runtime.memory: sizes parsed with their units, the dense mode's peak formula and its guard."""

import pytest

from meshcorr.errors import MemoryLimitError, ParameterError
from meshcorr.runtime.memory import (check_bijective_fits, check_dense_fits, default_max_memory, dense_memory,
                                     parse_memory)


@pytest.mark.parametrize("text, expected", [
    ("4GiB", 4 * 1024 ** 3), ("2G", 2 * 1024 ** 3), ("500MB", 500 * 1000 ** 2), ("1.5 kib", 1536),
    ("1024", 1024), (" 3 tb ", 3 * 1000 ** 4), ("10k", 10 * 1024),
])
def test_parse_memory_units(text, expected):
    assert parse_memory(text) == expected


def test_parse_memory_numbers_are_bytes():
    assert parse_memory(1000) == 1000
    assert parse_memory(2.9) == 2


@pytest.mark.parametrize("value", [0, -5, "0GB", "4 parsecs", "GB", True, None, float("nan")])
def test_parse_memory_refuses_what_is_not_a_positive_size(value):
    with pytest.raises(ParameterError, match="The 'max_memory' parameter must be a positive number of bytes"):
        parse_memory(value)


def test_dense_memory_formula():
    # 8 max(3 n1^2, n1^2 + 3 n2^2 [, n1^2 + n2^2 + 2 n1 n2]) bytes.
    assert dense_memory(100, 100) == 8 * 40_000
    assert dense_memory(100, 10) == 8 * 30_000
    assert dense_memory(10, 100) == 8 * (100 + 30_000)
    assert dense_memory(5000, 5000) / 1024 ** 2 == pytest.approx(763, abs=0.5)  # the docstring's figure
    # bijective: n1^2 + n2^2 + 2 n1 n2 beats 3 n1^2 when n2 is large enough
    assert dense_memory(100, 10, bijective=True) == dense_memory(100, 10)
    assert dense_memory(10, 10, bijective=True) == 8 * 400


def test_check_dense_fits_at_the_limit_and_over_it():
    need = dense_memory(300, 400)
    check_dense_fits(300, 400, need)
    check_dense_fits(300, 400, None)
    with pytest.raises(MemoryLimitError, match=r"300 x 300 and 400 x 400 .*mode='scalable'"):
        check_dense_fits(300, 400, need - 1)


def test_check_bijective_fits_cost_matrix():
    check_bijective_fits(100, 200, 16 * 100 * 200)
    with pytest.raises(MemoryLimitError, match=r"100 x 200 cost matrix"):
        check_bijective_fits(100, 200, 16 * 100 * 200 - 1)


def test_default_max_memory_is_a_fraction_of_what_is_available():
    limit = default_max_memory()
    assert limit is None or limit > 0


def test_the_coarse_path_is_refused_when_it_would_not_fit_and_the_message_says_what_fits():
    from meshcorr.runtime.memory import check_coarse_fits, coarse_path_fits, coarse_path_memory

    limit = 2 * 1024 ** 3
    largest = coarse_path_fits(limit)
    assert coarse_path_memory(largest, largest) <= limit < coarse_path_memory(largest + 1, largest + 1)
    check_coarse_fits(largest, largest, limit)
    check_coarse_fits(10 ** 7, 10 ** 7, None)  # no limit known
    # linear: doubling the vertices at most doubles the peak above the fixed base
    base = coarse_path_memory(0, 0)
    assert coarse_path_memory(2 * 10 ** 6, 2 * 10 ** 6) - base == 2 * (coarse_path_memory(10 ** 6, 10 ** 6) - base)
    with pytest.raises(MemoryLimitError, match=rf"1280000 and 1280000 vertices .* meshes of up to {largest} "
                                               r"vertices each fit\. .*--max-memory"):
        check_coarse_fits(1280000, 1280000, limit)
