"""parallel_map: the sequential loop's results, in order, from worker threads."""

import threading

import numpy as np
import pytest

import meshcorr.runtime.threads as threads_module
from meshcorr.runtime.threads import parallel_map

#: Seconds a task waits for the others before it gives up: a deadlock guard, not a timing.
PATIENCE = 60.0


@pytest.fixture
def four_cores(monkeypatch):
    """Four workers whatever the machine has, so that four tasks run at once."""
    monkeypatch.setattr(threads_module, "_cores", lambda: 4)


def test_results_are_the_sequential_ones_in_order():
    rng = np.random.default_rng(0)
    systems = [(rng.normal(size=(60, 60)) + 60 * np.eye(60), rng.normal(size=60)) for _ in range(5)]
    expected = [np.linalg.solve(a, b) for a, b in systems]
    got = parallel_map(lambda ab: np.linalg.solve(*ab), systems)
    assert len(got) == len(expected)
    for g, e in zip(got, expected):
        np.testing.assert_array_equal(g, e)


def test_tasks_run_at_the_same_time(four_cores):
    # Each task waits until all four have started: a sequential loop breaks the barrier.
    barrier = threading.Barrier(4, timeout=PATIENCE)
    threads = parallel_map(lambda _: (barrier.wait(), threading.get_ident())[1], range(4))
    assert len(set(threads)) == 4 and threading.get_ident() not in threads


def test_results_keep_the_item_order_when_tasks_finish_in_reverse(four_cores):
    # Task i finishes only after task i + 1 has: completion order is 3, 2, 1, 0.
    done = [threading.Event() for _ in range(4)]
    finished = []

    def task(i):
        if i < 3:
            assert done[i + 1].wait(PATIENCE), f"task {i + 1} never finished"
        finished.append(i)
        done[i].set()
        return 10 * i

    assert parallel_map(task, range(4)) == [0, 10, 20, 30]
    assert finished == [3, 2, 1, 0]


def test_the_error_of_the_first_failing_item_is_reraised(four_cores):
    # Tasks 1 and 3 fail; task 3 fails first, yet the error re-raised is task 1's, as in
    # the sequential loop. The other tasks still ran to their end.
    failed_3 = threading.Event()
    ran = []

    def task(i):
        if i == 1:
            assert failed_3.wait(PATIENCE), "task 3 never ran"
            raise ValueError("task 1 failed")
        if i == 3:
            failed_3.set()
            raise ValueError("task 3 failed")
        ran.append(i)
        return i

    with pytest.raises(ValueError, match="task 1 failed"):
        parallel_map(task, range(4))
    assert sorted(ran) == [0, 2]


def test_one_item_runs_in_the_calling_thread():
    assert parallel_map(lambda _: threading.get_ident(), [0]) == [threading.get_ident()]
    assert parallel_map(lambda x: x, []) == []
