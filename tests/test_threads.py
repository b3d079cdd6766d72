"""parallel_map: the sequential loop's results, in order, from worker threads."""

import threading

import numpy as np
import pytest

from meshcorr._threads import parallel_map


def test_results_are_the_sequential_ones_in_order():
    rng = np.random.default_rng(0)
    systems = [(rng.normal(size=(60, 60)) + 60 * np.eye(60), rng.normal(size=60)) for _ in range(5)]
    expected = [np.linalg.solve(a, b) for a, b in systems]
    got = parallel_map(lambda ab: np.linalg.solve(*ab), systems)
    assert len(got) == len(expected)
    for g, e in zip(got, expected):
        np.testing.assert_array_equal(g, e)


def test_the_first_task_error_is_reraised():
    def task(i):
        if i == 3:
            raise ValueError("task 3 failed")
        return i

    with pytest.raises(ValueError, match="task 3 failed"):
        parallel_map(task, range(6))


def test_one_item_runs_in_the_calling_thread():
    assert parallel_map(lambda _: threading.get_ident(), [0]) == [threading.get_ident()]
    assert parallel_map(lambda x: x, []) == []
